// Small helpers of the basic numeric types.
#include "engine/core/types.h"

namespace dynscope {

Points Pose::apply(const Points& local) const {
  const Mat3 r = rotation.normalized().toRotationMatrix();
  Points out = local * r.transpose();
  out.rowwise() += position.transpose();
  return out;
}

Aabb Aabb::of(const Points& points) {
  Aabb box;
  for (Eigen::Index i = 0; i < points.rows(); ++i) box.extend(Vec3(points.row(i).transpose()));
  return box;
}

}  // namespace dynscope
