// What the viewer's panels show about a scene: picked point, neighbourhoods, contacts, U-Net
// levels.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "engine/core/types.h"
#include "engine/geometry/point_cloud.h"
#include "engine/io/trace_file.h"
#include "engine/model/hierarchy.h"
#include "engine/scene/scene.h"
#include "render/scene_adapter.h"

namespace dynscope::app::viewer {

/// One point of the shown U-Net level at one frame.
struct PointInfo {
  int level_point = -1;  ///< Index into the level's points.
  int cloud_point =
      -1;  ///< Index of the level-0 point it is (the model's, or the sampled cloud's).
  int32_t object_id = -1;
  std::string object_name;
  Vec3 position = Vec3::Zero();  ///< World, scene units.
  Vec3 velocity = Vec3::Zero();  ///< World, units/s: central difference of neighbouring frames
                                 ///< (one-sided at the ends, zero for a single frame).
  bool has_velocity = false;     ///< False when the point has no identity over frames.
};

/// Position and velocity of level point `level_point` at `frame`: of the trace or level view the
/// data's levels come from (its frame only; a velocity when its level-0 points are the sampled
/// cloud), else of the sampled cloud (level 0). Throws ValueError for a point or frame out of
/// range.
PointInfo inspect_point(const render::SceneRenderData& data, int level_point, int frame);

/// Point `level_point` of level `level` of a model trace (its frame): position, object, and the
/// model point (level 0) it is, as cloud_point; no velocity (a trace holds one frame). Throws
/// ValueError for a level or point the trace does not have.
PointInfo inspect_trace_point(const ModelTrace& trace, const Scene& scene, int level,
                              int level_point);

/// World positions `[N_level,3]` of the level points at `frame` (the trace's frame when the data
/// has one; throws ValueError for another or a bad frame).
Points level_positions(const render::SceneRenderData& data, int frame);

/// One neighbour of a picked point.
struct NeighborEntry {
  int point = -1;  ///< Level point index.
  int32_t object_id = -1;
  double distance = 0.0;  ///< Scene units.
  /// Forward-pass trace only: |h(p_k - p_0)| of the list's traced PointConv, -1 when not traced.
  double weight = -1.0;
};

/// The picked point's neighbours as the model's convolutions see them at the shown level: the
/// object kNN (same object, the point itself excluded) and relational neighbours (other objects
/// within `radius`), both nearest first; the lists, k and radius of the trace or level view, and
/// the learned weights when a forward pass traced them. Matches the edges SceneRenderData draws.
struct Neighborhood {
  int k = 0;
  double radius = 0.0;
  std::vector<NeighborEntry> object;
  std::vector<NeighborEntry> relational;
  /// Model trace only: module paths of the PointConvs whose filter weights are listed ("" none).
  std::string object_conv, relational_conv;
};

/// Neighbourhood of `level_point` at `frame`. Throws ValueError for a point or frame out of range
/// and for data without a trace or level view.
Neighborhood point_neighborhood(const render::SceneRenderData& data, int level_point, int frame);

/// Minimum distance between the target's and the zone's points per frame, `[T]` (scene units), from
/// the level-0 `cloud` of `scene`; empty when the scene has no target or no zone.
std::vector<double> contact_distances(const Scene& scene, const ScenePointCloud& cloud);

/// Points of one U-Net level, in total and per object id.
struct LevelCount {
  int level = 0;
  double voxel = 0.0;   ///< Voxel edge that produced the level (0 at level 0).
  double radius = 0.0;  ///< Relational radius at the level.
  int points = 0;
  std::map<int32_t, int> per_object;
};

/// How one level-0 point's neighbour list differs between two traces of the same points (a
/// rollout-state trace and the hierarchy of the ground truth at its frame): the neighbours only
/// `a` lists and those only `b` lists, in list order. Empty when either trace lacks the list.
struct ListDifference {
  std::vector<int> only_a, only_b;
};
ListDifference neighbor_difference(const ModelTrace& a, const ModelTrace& b, LevelList list,
                                   int point);

/// Points per level and object of a trace or level view (the model's own hierarchy).
std::vector<LevelCount> trace_level_counts(const ModelTrace& trace);

}  // namespace dynscope::app::viewer
