// Kabsch rigid fit through Eigen::umeyama (SVD of the cross-covariance with the det sign fix).
#include "engine/geometry/kabsch.h"

#include <Eigen/SVD>
#include <string>

#include "engine/core/error.h"

namespace dynscope {

Pose fit_rigid_transform(const Points& source, const Points& target) {
  if (source.rows() != target.rows()) {
    throw ValueError("target", "has " + std::to_string(target.rows()) + " points, source has " +
                                   std::to_string(source.rows()));
  }
  if (source.rows() == 0) throw ValueError("source", "no points to fit");
  if (!source.allFinite()) throw ValueError("source", "contains a non-finite coordinate");
  if (!target.allFinite()) throw ValueError("target", "contains a non-finite coordinate");
  // umeyama flips the weakest singular direction when det(U)·det(V) < 0, so the result is a
  // proper rotation even for reflected, planar, collinear or single-point sets; in the degenerate
  // cases the undetermined rotation about the set's span is whatever the SVD picked.
  const Eigen::Matrix4d t = Eigen::umeyama(source.transpose(), target.transpose(), false);
  Pose pose;
  pose.position = t.block<3, 1>(0, 3);
  pose.rotation = Quat(Mat3(t.block<3, 3>(0, 0))).normalized();
  if (!pose.position.allFinite() || !pose.rotation.coeffs().allFinite()) {
    throw ValueError("source", "rigid fit did not converge (coordinates too large?)");
  }
  return pose;
}

}  // namespace dynscope
