// Kabsch rigid fit (SVD of the centred cross-covariance with the det sign fix, as Umeyama).
#include "engine/geometry/kabsch.h"

#include <Eigen/SVD>
#include <cmath>
#include <string>

#include "engine/core/error.h"

namespace dynscope {

Pose fit_rigid_transform(const Points& source, const Points& target) {
  if (source.rows() != target.rows()) {
    throw ValueError("target", "has " + std::to_string(target.rows()) + " points, source has " +
                                   std::to_string(source.rows()));
  }
  if (source.rows() == 0) throw ValueError("source", "no points to fit");
  // Umeyama's method without scaling, on fixed-size 3-vectors and a 3×3 SVD (Eigen::umeyama's
  // dynamic-size temporaries and matrix product cost several times more for a rollout's objects).
  // Centroids first, then the centred cross-covariance, so that far-from-origin sets keep their
  // precision; sums in locals so that they stay in registers.
  const Eigen::Index n = source.rows();
  const double* src = source.data();  // row-major x, y, z
  const double* dst = target.data();
  double sx = 0, sy = 0, sz = 0, tx = 0, ty = 0, tz = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    sx += src[3 * i];
    sy += src[3 * i + 1];
    sz += src[3 * i + 2];
    tx += dst[3 * i];
    ty += dst[3 * i + 1];
    tz += dst[3 * i + 2];
  }
  // A sum is finite when every coordinate is, or finite ones overflow (checked below).
  if (!std::isfinite(sx + sy + sz) && !source.allFinite()) {
    throw ValueError("source", "contains a non-finite coordinate");
  }
  if (!std::isfinite(tx + ty + tz) && !target.allFinite()) {
    throw ValueError("target", "contains a non-finite coordinate");
  }
  const double inv_n = 1.0 / static_cast<double>(n);
  const Vec3 source_mean(sx * inv_n, sy * inv_n, sz * inv_n);
  const Vec3 target_mean(tx * inv_n, ty * inv_n, tz * inv_n);
  double cxx = 0, cxy = 0, cxz = 0, cyx = 0, cyy = 0, cyz = 0, czx = 0, czy = 0, czz = 0;
  for (Eigen::Index i = 0; i < n; ++i) {  // Σ (d_i − d̄)(s_i − s̄)ᵀ
    const double ax = src[3 * i] - source_mean.x(), ay = src[3 * i + 1] - source_mean.y(),
                 az = src[3 * i + 2] - source_mean.z();
    const double bx = dst[3 * i] - target_mean.x(), by = dst[3 * i + 1] - target_mean.y(),
                 bz = dst[3 * i + 2] - target_mean.z();
    cxx += bx * ax;
    cxy += bx * ay;
    cxz += bx * az;
    cyx += by * ax;
    cyy += by * ay;
    cyz += by * az;
    czx += bz * ax;
    czy += bz * ay;
    czz += bz * az;
  }
  Mat3 sigma;
  sigma << cxx, cxy, cxz, cyx, cyy, cyz, czx, czy, czz;
  sigma *= inv_n;
  if (!sigma.allFinite() || !source_mean.allFinite() || !target_mean.allFinite()) {
    throw ValueError("source", "rigid fit did not converge (coordinates too large?)");
  }
  // The weakest singular direction is flipped when det(U)·det(V) < 0, so the result is a proper
  // rotation even for reflected, planar, collinear or single-point sets; in the degenerate cases
  // the undetermined rotation about the set's span is whatever the SVD picked.
  const Eigen::JacobiSVD<Mat3> svd(sigma, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Vec3 flip = Vec3::Ones();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0.0) flip.z() = -1.0;
  const Mat3 rotation = svd.matrixU() * flip.asDiagonal() * svd.matrixV().transpose();
  Pose pose;
  pose.position = target_mean - rotation * source_mean;
  pose.rotation = Quat(rotation).normalized();
  if (!pose.position.allFinite() || !pose.rotation.coeffs().allFinite()) {
    throw ValueError("source", "rigid fit did not converge (coordinates too large?)");
  }
  return pose;
}

}  // namespace dynscope
