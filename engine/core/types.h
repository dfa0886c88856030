// Basic numeric types shared by every engine module (Eigen based, z-up metres-like units).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <limits>
#include <vector>

namespace dynscope {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
/// Unit quaternion; files and APIs order its coefficients w, x, y, z.
using Quat = Eigen::Quaterniond;
/// Row-major `[N,3]` array of positions (scene units).
using Points = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
/// Row-major `[F,3]` array of triangle vertex indices.
using Faces = Eigen::Matrix<int32_t, Eigen::Dynamic, 3, Eigen::RowMajor>;
/// Row-major `[M,K]` array of point indices; -1 where the matching mask entry is 0.
using IndexMatrix = Eigen::Matrix<int32_t, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
/// Row-major `[M,K]` validity mask (1 valid, 0 masked).
using MaskMatrix = Eigen::Matrix<uint8_t, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// Rigid transform x' = rotation * x + translation.
struct Pose {
  Vec3 position = Vec3::Zero();
  Quat rotation = Quat::Identity();

  /// Applies the pose to every row of `local` (object frame) and returns world points.
  Points apply(const Points& local) const;
  /// Applies the pose to one point.
  Vec3 apply(const Vec3& local) const { return rotation * local + position; }
};

/// Axis-aligned bounding box; empty when min > max.
struct Aabb {
  Vec3 min = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 max = Vec3::Constant(-std::numeric_limits<double>::infinity());

  bool empty() const { return (min.array() > max.array()).any(); }
  void extend(const Vec3& p) {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  }
  void extend(const Aabb& b) {
    if (!b.empty()) {
      extend(b.min);
      extend(b.max);
    }
  }
  /// Bounding box of the rows of `points` (empty for zero rows).
  static Aabb of(const Points& points);
};

}  // namespace dynscope
