// Rigid projection of predicted points: one Kabsch transform per rigid object and step.
#pragma once

#include <cstdint>
#include <vector>

#include "engine/core/types.h"
#include "engine/geometry/point_cloud.h"
#include "engine/scene/scene.h"

namespace dynscope {

/// Projects each rigid object's predicted points onto the closest rigid motion of its rest
/// points (fit_rigid_transform(rest, predicted), paper §3.6); points of non-rigid objects stay
/// as predicted.
class RigidProjector {
 public:
  /// `cloud` gives every point's object index and rest coordinate; `rigid` `[O]` flags objects
  /// (indexed like Scene::objects). Throws ValueError if a point's object index is outside `rigid`.
  RigidProjector(const ScenePointCloud& cloud, const std::vector<uint8_t>& rigid);
  /// The projector of a scene's rollouts: its objects' own rigid flags (Object::rigid).
  RigidProjector(const ScenePointCloud& cloud, const Scene& scene);

  /// Returns the projected points `[N,3]` for `predicted` `[N,3]` (world frame) and writes one
  /// pose per object into `poses` when given (identity for non-rigid objects or objects without
  /// points). Throws ValueError if `predicted` does not have N rows or is not finite.
  Points project(const Points& predicted, std::vector<Pose>* poses = nullptr) const;

  /// Lifts every rigid object whose lowest projected point is below z = `floor_z` by the
  /// difference (a floor clamp for physics-free baselines), updating `points` and `poses`.
  void clamp_to_floor(Points& points, std::vector<Pose>& poses, double floor_z = 0.0) const;

  int num_objects() const { return static_cast<int>(rigid_.size()); }
  /// The rigid flag of every object `[O]`, as given.
  const std::vector<uint8_t>& rigid() const { return rigid_; }

 private:
  std::vector<uint8_t> rigid_;
  std::vector<std::vector<Eigen::Index>> rows_;  // point rows of each object
  std::vector<Points> rest_;                     // rest coordinates of each object's points
  Eigen::Index size_ = 0;
};

}  // namespace dynscope
