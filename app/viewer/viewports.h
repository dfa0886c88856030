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

/// Width of the side panel (pixels; 0 when the UI is hidden).
float panel_width(const WindowLayout& layout);
/// Height of the bottom strip (timeline, plus the error strip with a rollout; 0 when hidden).
float timeline_height(const WindowLayout& layout, bool has_rollout);
/// Fits `camera` to `bounds` in the part of the window the panels leave free (half of it per
/// viewport when `split`), then shifts the view so the scene is centred there: the 3D view itself
/// spans the whole window, behind the panels.
void fit_camera_to_free_area(render::Camera& camera, const Aabb& bounds, const WindowLayout& layout,
                             bool has_rollout, bool split);

/// What one viewport of the 3D view draws: `scene` seen by `camera` in `rect` of the window
/// (side by side: two viewports share one camera, shifted to each one's centre).
struct Viewport {
  render::RenderScene scene;
  render::Camera camera;
  render::Rect rect;    ///< Pixels, origin bottom-left (GL convention), full window height.
  std::string caption;  ///< Drawn at the viewport's top ("" for none).
  /// `[scene.points]` the set each point layer draws (kNone: not selectable, e.g. neighbourhoods).
  std::vector<PickSet> layer_sets;
};

/// What a click in one viewport can hit: the viewport's selectable layers, all opaque and pickable
/// (a translucent ghost is picked where it is drawn in front), its meshes as occluders, and the
/// set each layer holds.
struct PickScene {
  render::RenderScene scene;
  std::vector<PickSet> sets;  ///< `[scene.points]`.
};

/// The pick scene of `viewport` of `state` (level points only once the model's trace is shown
/// when a checkpoint is in use).
PickScene pick_scene(const ViewerState& state, const Viewport& viewport);

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
