// RolloutDocument: a rollout shown in the viewer, its GPU-facing series built once, and the
// RenderScene of any frame in each display mode (the same layers `dynscope render` draws).
#pragma once

#include <memory>
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

/// A rollout shown in the viewer: what render derives once to draw it (series uploaded once, so
/// scrubbing re-uploads nothing; meshes, radius, bounds, grid), and where it came from. Frames
/// are drawn by render::rollout_frame, as `dynscope render` draws them.
struct RolloutDocument : render::RolloutRenderData {
  std::string path;  ///< File it came from, or a description ("rollout of A.pt").
};

/// Validates `rollout` (throws ValueError naming `path`) and builds its document; `scene` (may
/// be null) gives meshes and must be the scene the rollout started from.
std::unique_ptr<RolloutDocument> make_rollout_document(Rollout rollout, const std::string& path,
                                                       const Scene* scene);

/// Appends `other`'s predicted points at `frame` as a translucent, unpickable ghost (a compared
/// rollout over this one). Throws ValueError for a frame outside `other`.
void add_prediction_ghost(render::RenderScene& out, const RolloutDocument& other, int frame);

/// First frame whose value exceeds `threshold` (strictly), or -1 when none does.
int first_frame_over(const std::vector<double>& values, double threshold);

}  // namespace dynscope::app::viewer
