// Turns engine data (a Scene, or a rollout's true/predicted points) into RenderScenes
// (the mjv_updateScene half: plain description in, no GL).
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "engine/geometry/neighbors.h"
#include "engine/geometry/point_cloud.h"
#include "engine/io/trace_file.h"
#include "engine/rollout/level_view.h"
#include "engine/scene/rollout.h"
#include "engine/scene/scene.h"
#include "render/render_scene.h"
#include "render/view_spec.h"

namespace dynscope::render {

/// A ground grid under `bounds` (plane z = 0, or the lowest point if it lies below 0) with a
/// round spacing; an empty box gives the default grid.
GroundGrid grid_for_bounds(const Aabb& bounds);

/// Everything derived once from a Scene to draw any of its frames: shared mesh geometry, the
/// sampled point cloud of every frame as one PointSeries, and the points of the view's U-Net level.
/// Building it samples points, so it is done once per scene and view, not per frame.
///
/// Levels, voxels, neighbour lists and interaction points are the model's own and are handed in
/// as a ModelTrace: one forward pass (`dynscope trace`, with the learned filter weights), or a
/// level view (engine/rollout/level_view.h: the hierarchy the model builds, no forward pass).
/// They exist at the trace's frame only. Without one, only level 0 (the sampled points) can be
/// drawn; nothing here re-derives the hierarchy or searches neighbours.
class SceneRenderData {
 public:
  /// Copies `scene` (validated; throws ValueError) and prepares what `view` asks for. A `trace`
  /// must have the view's level (ValueError "level") and a frame of the scene (ValueError
  /// "trace"); without one the view's level must be 0 (ValueError "level").
  SceneRenderData(const Scene& scene, const ViewSpec& view,
                  std::shared_ptr<const ModelTrace> trace = nullptr);

  /// Replaces the trace or level view the levels come from (e.g. the level view of another
  /// frame); throws as the constructor does for it, and ValueError for null.
  void set_levels(std::shared_ptr<const ModelTrace> trace);

  int num_frames() const { return scene_.num_frames(); }
  const Scene& scene() const { return scene_; }
  /// U-Net level the data shows.
  int level() const { return level_; }
  /// Level-0 voxel edge used (view's, or default_sampling_voxel of the scenario).
  double voxel() const { return voxel_; }
  /// Voxel edge of the view's level: the trace's (level ≥ 1), else the sampling voxel.
  double level_voxel() const;
  /// Relational radius of the view's level from the trace, 0 without one.
  double level_radius() const;
  /// Sphere radius used for points (view's, or 0.3 x level voxel).
  float point_radius() const;
  /// All level-0 points (identity kept over frames), `[N]` with object ids.
  const ScenePointCloud& cloud() const { return cloud_; }
  /// Bounds of every object over frames [first, last] (inclusive).
  Aabb bounds(int first, int last) const;

  /// The model trace or level view the levels come from, or null.
  const ModelTrace* trace() const { return trace_.get(); }
  /// Number of points of the view's level (the cloud's at level 0 without a trace).
  int level_size() const;

  /// The level's points at one frame and the neighbourhoods of one of them.
  struct LevelNeighbors {
    Points positions;             ///< `[N_level,3]` level points at the frame.
    std::vector<int32_t> object;  ///< `[N_level]` object id per level point.
    NeighborList same;        ///< `[1,k]` same-object kNN of the picked point (itself included).
    NeighborList relational;  ///< `[1,k]` other-object kNN within level_radius().
    /// Forward-pass traces only: ‖h(p_k − p_0)‖ of the first traced PointConv over each list entry
    /// (`[k]`, 0 where masked), empty when the trace holds no filter weights for the point; the
    /// conv's module path.
    std::vector<double> same_weight, relational_weight;
    std::string same_conv, relational_conv;
    /// Level ≥ 1: level−1 points pooled into the picked point (down list) and the
    /// level−1 points whose upsampling reads it (up list), with their positions `[n,3]`.
    std::vector<int32_t> sources, feeds;
    Points source_positions = Points(0, 3), feed_positions = Points(0, 3);
  };
  /// Neighbourhoods of level point `picked` at `frame` (what the view draws and the viewer lists):
  /// the trace's lists (k is the model's K); `frame` must be the trace's. Throws ValueError for a
  /// bad frame or point, and without a trace.
  LevelNeighbors level_neighbors(int frame, int picked) const;

  /// The RenderScene of `frame` under `view` (same layers/level the data was built for; the
  /// picked point indexes the level's points). Throws ValueError for a bad frame or picked point.
  RenderScene frame(int frame, const ViewSpec& view) const;
  /// Short captions of the layers shown (for image labels).
  std::vector<std::string> legend(const ViewSpec& view) const;

 private:
  void add_neighborhoods(RenderScene& out, int frame, const ViewSpec& view) const;
  /// Interaction points: the model's (sender → receiver pairs and their faces) from a mesh-input
  /// trace at its frame; none for a model that reads points.
  void add_interaction_points(RenderScene& out, int frame) const;
  void add_trace_interaction_points(RenderScene& out, int frame) const;

  void check_trace_frame(int frame) const;
  /// Throws ValueError(what) without a trace or level view.
  void require_levels(const char* what) const;

  Scene scene_;
  std::shared_ptr<const ModelTrace> trace_;
  int level_ = 0;
  double voxel_ = 0.05;
  float point_radius_ = 0.01f;
  std::vector<std::shared_ptr<MeshGeometry>> geometry_;  ///< Per object (rigid: local frame).
  ScenePointCloud cloud_;
  std::shared_ptr<PointSeries> cloud_series_;  ///< Level-0 points, all frames.
  std::shared_ptr<PointSeries> level_series_;  ///< Level points, all frames.
  std::vector<int32_t> level_object_;          ///< Object id per level point.
};

/// True when `view` draws what only the model's hierarchy holds: a level above 0, a picked
/// point's neighbourhoods, level-1+ voxels or interaction points.
bool view_needs_levels(const ViewSpec& view);

/// The model whose hierarchy `view` shows of `scene` when no trace is given: the scenario's scale
/// preset (level_view_config), reading meshes when the view asks for interaction points (a model
/// that reads points has none), else points.
ModelConfig level_view_config(const Scene& scene, const ViewSpec& view);

/// Level views of `scene` for `view` without a trace: level_view_config, the view's voxel.
std::shared_ptr<LevelViews> make_level_views(const Scene& scene, const ViewSpec& view);

/// True and predicted point sets of a rollout, `[T,N,3]` each, as two series built once; the
/// prediction carries per-point errors |pred - truth| as scalars.
struct ComparisonSeries {
  std::shared_ptr<PointSeries> truth;
  std::shared_ptr<PointSeries> prediction;
  float max_error = 0.0f;  ///< Over all frames and points.
};

/// Builds the comparison from per-frame point arrays of equal shapes and per-point object ids
/// (`[N]`, used for categorical colours). Throws ValueError on shape mismatch.
ComparisonSeries make_comparison_series(const std::vector<Points>& truth,
                                        const std::vector<Points>& predicted,
                                        const std::vector<int32_t>& object_ids);

/// A rollout with what is derived from it once to draw any frame (the rollout's SceneRenderData):
/// the truth/prediction series (uploaded once, so scrubbing re-uploads nothing), mesh geometry
/// of its rigid objects when the scene it started from is given, point radius, bounds and grid.
/// Shared by `dynscope render` and the viewer.
struct RolloutRenderData {
  Rollout rollout;
  ComparisonSeries series;
  std::optional<Scene> scene;  ///< Scene the rollout started from (meshes, truth poses).
  /// Per pose object (Rollout::pose_object_ids): its mesh, or null (no scene, not rigid, no mesh).
  std::vector<std::shared_ptr<MeshGeometry>> geometry;
  float point_radius = 0.01f;  ///< Sphere radius: 0.3 x sampling voxel (else 1% of the extent).
  Aabb bounds;                 ///< Truth and prediction over all frames.
  GroundGrid grid;

  int num_frames() const { return rollout.num_frames(); }
  /// Largest per-point error over all frames (scene units).
  float max_error() const { return series.max_error; }
};

/// Validates `rollout` (throws ValueError, also for no frames) and prepares it. `scene` (may be
/// null) gives meshes; one with fewer frames than the rollout is ignored. `point_radius` > 0
/// overrides the default radius.
RolloutRenderData make_rollout_render_data(Rollout rollout, const Scene* scene,
                                           float point_radius = 0.0f);

/// The RenderScene of `frame` as `view` asks: the grid, meshes at the predicted poses when
/// view.layers.prediction (else the true poses), translucent so the points stay visible, and the
/// point layers of add_comparison_layers. Throws ValueError for a frame outside the rollout.
RenderScene rollout_frame(const RolloutRenderData& data, int frame, const ViewSpec& view);

/// Appends the rollout's point layers for `frame` to `out` as `view.layers` asks: truth points,
/// predicted points (categorical, or error through the colormap when `layers.error`), and a
/// translucent ghost of the other set when `layers.ghost`. `radius` is the sphere radius.
void add_comparison_layers(RenderScene& out, const ComparisonSeries& series, int frame,
                           const ViewSpec& view, float radius);

/// Name of the predicted points' layer in a rollout's RenderScene.
inline constexpr const char* kPredictionLayer = "prediction";

/// An explanation's per-point shares drawn over a rollout (plain data: the engine computes them).
struct PointAttribution {
  std::vector<float> shares;   ///< `[N]` each rollout point's share as a source (0: none).
  std::vector<int> explained;  ///< Points whose prediction is explained (drawn under a halo).
};

/// The rollout's predicted points over all frames coloured by `attribution`: sources through the
/// "turbo" colormap by share relative to the largest (square-root scaled, so small shares still
/// show), points under 1 % of the largest light grey. Throws ValueError when the shares or
/// explained points do not fit the rollout's points.
std::shared_ptr<PointSeries> make_attribution_series(const RolloutRenderData& data,
                                                     const PointAttribution& attribution);

/// Draws `series` (make_attribution_series) at `frame` in place of the kPredictionLayer layer of
/// `out` (appended when there is none) and the explained points under translucent halos.
void add_attribution_layers(RenderScene& out, const std::shared_ptr<PointSeries>& series,
                            const PointAttribution& attribution, int frame, float radius);

}  // namespace dynscope::render
