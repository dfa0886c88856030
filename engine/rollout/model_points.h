// The points a model reads from a scene: surface samples (point input) or simplified mesh
// vertices with faces (mesh input), each with a rest coordinate so frames follow from poses.
#pragma once

#include <cstdint>
#include <string>

#include "engine/geometry/point_cloud.h"
#include "engine/model/model_config.h"
#include "engine/scene/scene.h"

namespace dynscope {

/// How model points are drawn from a scene.
struct SamplingOptions {
  InputMode input = InputMode::kPoints;
  double voxel = 0.0;       ///< Grid voxel (points) or vertex-clustering voxel (mesh); 0: default.
  double oversample = 8.0;  ///< Surface samples per voxel² of area (point input).
  uint64_t seed = 0;        ///< Surface sampling seed (point input).
};

/// The paper's initial sampling voxel: 0.2 for Kubric-scale scenarios ("movi-*"), 0.05 otherwise.
double default_sampling_voxel(const std::string& scenario);

/// "kubric" for "movi-*" scenarios, "physion" otherwise (the ModelConfig::preset name).
std::string default_scale_preset(const std::string& scenario);

/// Gravity of a scenario in scene units / s² (10 for "movi-*", 9.81 otherwise).
double default_gravity(const std::string& scenario);

/// Model points of one scene with identities that persist over frames.
struct ModelPoints {
  ScenePointCloud cloud;      ///< Rest coordinates, object index and id of every point.
  Faces faces = Faces(0, 3);  ///< `[F,3]` triangles over the points (mesh input; else empty).
  double voxel = 0.0;         ///< Voxel the points were drawn with.

  Eigen::Index size() const { return cloud.size(); }
  /// World positions `[N,3]` at `frame`; throws ValueError for a frame outside the scene.
  Points positions(const Scene& scene, int frame) const { return cloud.positions(scene, frame); }
};

/// Point input: build_point_cloud at the voxel. Mesh input: each object's scaled mesh simplified
/// by vertex clustering at the voxel (object frame), faces re-indexed into one list. Throws
/// ValueError for a bad voxel or scene, and for deformable objects with mesh input.
ModelPoints build_model_points(const Scene& scene, const SamplingOptions& options);

}  // namespace dynscope
