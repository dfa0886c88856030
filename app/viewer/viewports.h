// What the 3D view draws for a ViewerState: one viewport, or two side by side (plain data; the
// renderer draws each into its rectangle).
#pragma once

#include <string>
#include <vector>

#include "app/viewer/viewer_state.h"
#include "render/camera.h"
#include "render/render_scene.h"
#include "render/renderer.h"
#include "render/view_spec.h"

namespace dynscope::app::viewer {

/// Which point set a viewport's pickable layer holds.
enum class PickSet { kNone, kLevel, kPrediction, kTruth, kCompared };

/// "level points", "prediction", "truth", "compared prediction" ("" for none).
const char* pick_set_name(PickSet set);

/// What one viewport of the 3D view draws: `scene` seen by `camera` in `rect` of the window
/// (side by side: two viewports share one camera, shifted to each one's centre).
struct Viewport {
  render::RenderScene scene;
  render::Camera camera;
  render::Rect rect;    ///< Pixels, origin bottom-left (GL convention), full window height.
  std::string caption;  ///< Drawn at the viewport's top ("" for none).
  PickSet pick_set = PickSet::kNone;  ///< The set a click in this viewport selects from.
  int pick_layer = -1;                ///< Index into scene.points of that set's layer.
};

/// The viewports for the current state (none without a document).
std::vector<Viewport> build_viewports(const ViewerState& state);

/// Only the shown level's points of the current frame (pickable), so a pick hit's index is a
/// level point index. Throws ValueError without a scene.
render::RenderScene level_pick_scene(const ViewerState& state);

/// Index of the viewport that pixel column `x` lies in (0 with a single viewport).
int viewport_at(const std::vector<Viewport>& viewports, int x);

/// The view `state` shows a rollout with: layers set as asked and an explicit colour range (one
/// range for both rollouts of a comparison, so equal colours mean equal errors).
render::ViewSpec rollout_view(const ViewerState& state, bool prediction, bool truth, bool ghost);

}  // namespace dynscope::app::viewer
