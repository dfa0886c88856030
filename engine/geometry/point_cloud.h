// The model's point state: surface samples per object, grid-downsampled in the rest frame.
#pragma once

#include <cstdint>
#include <vector>

#include "engine/scene/scene.h"

namespace dynscope {

/// How points are drawn from object surfaces.
struct PointCloudOptions {
  double voxel = 0.05;      ///< Grid downsampling voxel edge (scene units).
  double oversample = 8.0;  ///< Surface samples per voxel-face area (voxel²) before downsampling.
  uint64_t seed = 0;        ///< Sampling seed.
};

/// Points that keep their identity over time: each has an object index and a rest-frame
/// (object-local, scaled) coordinate, so its world position at any frame follows from the pose.
struct ScenePointCloud {
  Points rest = Points(0, 3);      ///< `[N,3]` object-frame coordinates (scale applied).
  std::vector<int32_t> object;     ///< `[N]` index into Scene::objects.
  std::vector<int32_t> object_id;  ///< `[N]` Object::id.
  std::vector<int32_t> particle;   ///< `[N]` particle index for deformable objects, -1 if rigid.

  Eigen::Index size() const { return rest.rows(); }
  /// World positions `[N,3]` at `frame` (rigid: pose applied; deformable: its particle). Throws
  /// ValueError for a frame outside the scene or points that do not match the scene.
  Points positions(const Scene& scene, int frame) const;
  /// Number of points of object index `i`.
  int64_t count_of(int i) const;
  /// `[N]` 1 for the points of static objects (Object::is_static) of `scene`, else 0. Throws
  /// ValueError when the points do not match the scene.
  std::vector<uint8_t> static_mask(const Scene& scene) const;
};

/// Samples each object's scaled mesh uniformly by area (ceil(oversample · area / voxel²) samples,
/// seeded with derive_seed(seed, object index)) and grid-downsamples it per object in the object
/// frame, keeping the sample nearest each voxel centre. Deformable objects use their frame-0
/// particles (grid-downsampled; `rest` then holds frame-0 world positions). Throws ValueError for
/// bad options ("voxel", "oversample"), an invalid scene, or an object without surface area.
ScenePointCloud build_point_cloud(const Scene& scene, const PointCloudOptions& options);

}  // namespace dynscope
