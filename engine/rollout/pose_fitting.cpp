// RigidProjector: per-object Kabsch fits from rest points to predicted points.
#include "engine/rollout/pose_fitting.h"

#include <string>

#include "engine/core/error.h"
#include "engine/geometry/kabsch.h"

namespace dynscope {

RigidProjector::RigidProjector(const ScenePointCloud& cloud, const std::vector<uint8_t>& rigid)
    : rigid_(rigid), rows_(rigid.size()), rest_(rigid.size()), size_(cloud.size()) {
  for (Eigen::Index p = 0; p < cloud.size(); ++p) {
    const int32_t i = cloud.object.at(static_cast<size_t>(p));
    if (i < 0 || static_cast<size_t>(i) >= rigid.size()) {
      throw ValueError("object", "point " + std::to_string(p) + " refers to object index " +
                                     std::to_string(i) + " of " + std::to_string(rigid.size()));
    }
    rows_[static_cast<size_t>(i)].push_back(p);
  }
  for (size_t i = 0; i < rigid.size(); ++i) {
    rest_[i].resize(static_cast<Eigen::Index>(rows_[i].size()), 3);
    for (size_t r = 0; r < rows_[i].size(); ++r) {
      rest_[i].row(static_cast<Eigen::Index>(r)) = cloud.rest.row(rows_[i][r]);
    }
  }
}

namespace {
std::vector<uint8_t> rigid_flags(const Scene& scene) {
  std::vector<uint8_t> rigid;
  for (const Object& o : scene.objects) rigid.push_back(o.rigid ? 1 : 0);
  return rigid;
}
}  // namespace

RigidProjector::RigidProjector(const ScenePointCloud& cloud, const Scene& scene)
    : RigidProjector(cloud, rigid_flags(scene)) {}

Points RigidProjector::project(const Points& predicted, std::vector<Pose>* poses) const {
  if (predicted.rows() != size_) {
    throw ValueError("predicted", "has " + std::to_string(predicted.rows()) + " points, expected " +
                                      std::to_string(size_));
  }
  if (!predicted.allFinite()) throw ValueError("predicted", "non-finite position");
  Points out = predicted;
  if (poses) poses->assign(rigid_.size(), Pose{});
  for (size_t i = 0; i < rigid_.size(); ++i) {
    if (!rigid_[i] || rows_[i].empty()) continue;
    Points target(rest_[i].rows(), 3);
    for (size_t r = 0; r < rows_[i].size(); ++r) {
      target.row(static_cast<Eigen::Index>(r)) = predicted.row(rows_[i][r]);
    }
    const Pose pose = fit_rigid_transform(rest_[i], target);
    const Points fitted = pose.apply(rest_[i]);
    for (size_t r = 0; r < rows_[i].size(); ++r) {
      out.row(rows_[i][r]) = fitted.row(static_cast<Eigen::Index>(r));
    }
    if (poses) (*poses)[i] = pose;
  }
  return out;
}

void RigidProjector::clamp_to_floor(Points& points, std::vector<Pose>& poses,
                                    double floor_z) const {
  for (size_t i = 0; i < rigid_.size() && i < poses.size(); ++i) {
    if (!rigid_[i] || rows_[i].empty()) continue;
    double lowest = points(rows_[i][0], 2);
    for (Eigen::Index r : rows_[i]) lowest = std::min(lowest, points(r, 2));
    if (lowest >= floor_z) continue;
    for (Eigen::Index r : rows_[i]) points(r, 2) += floor_z - lowest;
    poses[i].position.z() += floor_z - lowest;
  }
}

}  // namespace dynscope
