// RolloutDocument: a rollout shown in the viewer, its GPU-facing series built once, and the
// RenderScene of any frame in each display mode (the same layers `dynscope render` draws).
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "engine/scene/rollout.h"
#include "engine/scene/scene.h"
#include "render/render_scene.h"
#include "render/scene_adapter.h"
#include "render/view_spec.h"

namespace dynscope::app::viewer {

/// How a rollout is shown. "The other set" is the compared rollout's prediction when one is
/// loaded (a second checkpoint, or the original of a what-if), else the ground truth.
enum class RolloutMode {
  kPrediction,  ///< Predicted points only.
  kTruth,       ///< Ground-truth points only.
  kGhost,       ///< Prediction with the other set translucent.
  kSideBySide,  ///< Two viewports, one camera: the other set left, the prediction right.
};

/// "prediction", "truth", "ghost" or "side by side".
const char* rollout_mode_name(RolloutMode mode);

/// A rollout with what is derived from it once: the truth/prediction series (uploaded once, so
/// scrubbing re-uploads nothing), mesh geometry of its rigid objects when the scene it names was
/// found, point radius, bounds and ground grid.
struct RolloutDocument {
  std::string path;  ///< File it came from, or a description ("rollout of A.pt").
  Rollout rollout;
  render::ComparisonSeries series;
  std::optional<Scene> scene;  ///< Scene the rollout started from (meshes, truth poses).
  /// Per pose object (Rollout::pose_object_ids): its mesh, or null (no scene, not rigid, no mesh).
  std::vector<std::shared_ptr<render::MeshGeometry>> geometry;
  float point_radius = 0.01f;  ///< Sphere radius: 0.3 x sampling voxel (else 1% of the extent).
  Aabb bounds;                 ///< Truth and prediction over all frames.
  render::GroundGrid grid;

  int num_frames() const { return rollout.num_frames(); }
  /// Largest per-point error over all frames (scene units).
  float max_error() const { return series.max_error; }
};

/// Validates `rollout` (throws ValueError) and builds its document; `scene` (may be null) gives
/// meshes and must be the scene the rollout started from.
std::unique_ptr<RolloutDocument> make_rollout_document(Rollout rollout, const std::string& path,
                                                       const Scene* scene);

/// The RenderScene of `frame` of `doc` as `dynscope render` draws it: the view's grid, meshes at
/// the predicted poses when view.layers.prediction (else the true poses), and the point layers of
/// render::add_comparison_layers (prediction, truth, ghost, error colours, colormap and range).
/// Throws ValueError for a frame outside the rollout.
render::RenderScene rollout_frame(const RolloutDocument& doc, int frame,
                                  const render::ViewSpec& view);

/// Appends `other`'s predicted points at `frame` as a translucent, unpickable ghost (a compared
/// rollout over this one). Throws ValueError for a frame outside `other`.
void add_prediction_ghost(render::RenderScene& out, const RolloutDocument& other, int frame);

/// First frame whose value exceeds `threshold` (strictly), or -1 when none does.
int first_frame_over(const std::vector<double>& values, double threshold);

}  // namespace dynscope::app::viewer
