// Viewports of the 3D view: the RenderScene(s) of the current frame and where each is drawn.
#include "app/viewer/viewports.h"

#include <algorithm>
#include <cmath>

#include "engine/core/error.h"
#include "render/scene_adapter.h"

namespace dynscope::app::viewer {
namespace {

constexpr float kPanelWidth = 370.0f;
constexpr float kTimelineHeight = 58.0f;
constexpr float kErrorStripHeight = 64.0f;  // added under the timeline while a rollout is shown
const render::Color kSelectionColor(0.95f, 0.10f, 0.55f);

// The set a rollout layer draws, told by its series (each document's series are built once).
PickSet rollout_layer_set(const ViewerState& state, const render::PointLayer& layer) {
  const RolloutDocument* a = state.rollout_document();
  const RolloutDocument* b = state.compared_rollout();
  if (a && layer.series == a->series.prediction) return PickSet::kPrediction;
  // The explanation's colouring of the same predicted points.
  if (a && layer.series && layer.series == state.attribution_series()) return PickSet::kPrediction;
  if (a && layer.series == a->series.truth) return PickSet::kTruth;
  if (b && layer.series == b->series.prediction) return PickSet::kCompared;
  if (b && layer.series == b->series.truth) return PickSet::kTruth;  // the same scene's truth
  return PickSet::kNone;
}

// Says when the level layers show another frame than the timeline (an observed frame the model
// cannot trace shows the first frame it can).
std::string level_caption(const ViewerState& state) {
  if (state.level_frame() == state.current_frame()) return "";
  return "model levels at frame " + std::to_string(state.level_frame()) +
         " (the first the model can trace)";
}

// `v` without what only the model's hierarchy can draw while the level data has none yet (a
// checkpoint's trace still being captured): the pick's neighbourhoods and interaction points.
render::ViewSpec drawable(const ViewerState& state, render::ViewSpec v) {
  if (state.active_data()->trace() == nullptr) {
    v.picked_point = -1;
    v.layers.interaction_points = false;
  }
  return v;
}

// The level layers (points, voxels, neighbourhoods, interaction points) over a rollout frame.
void add_scene_layers(const ViewerState& state, render::RenderScene& out) {
  const render::ViewSpec& view = state.view();
  const render::ViewLayers& l = view.layers;
  const SceneDocument* doc = state.scene_document();
  if (!doc || view.frame >= doc->scene.num_frames() ||
      !(l.level_points || l.voxels || l.neighborhoods || l.interaction_points)) {
    return;
  }
  render::ViewSpec v = view;
  v.layers.grid = v.layers.meshes = v.layers.ground_truth = v.layers.prediction = false;
  render::RenderScene levels = state.active_data()->frame(state.level_frame(), drawable(state, v));
  out.points.insert(out.points.end(), levels.points.begin(), levels.points.end());
  out.lines.insert(out.lines.end(), levels.lines.begin(), levels.lines.end());
  out.boxes.insert(out.boxes.end(), levels.boxes.begin(), levels.boxes.end());
}

// The selected rollout point (large, magenta) and its counterpart in the other set, joined by the
// error vector: drawn over every rollout viewport, never picked.
void add_selection_marker(const ViewerState& state, int frame, Viewport& port) {
  const std::shared_ptr<render::PointSeries>& marker = state.selection_marker();
  if (!marker || frame >= marker->num_frames) return;
  const RolloutDocument& doc = state.rollout();
  render::PointLayer layer;
  layer.name = "selected point";
  layer.series = marker;
  layer.frame = frame;
  layer.coloring = render::PointColoring::kUniform;
  layer.color = kSelectionColor;
  layer.radius = 1.8f * doc.point_radius;
  layer.pickable = false;
  port.scene.points.push_back(std::move(layer));
  port.layer_sets.push_back(PickSet::kNone);
  render::LineSet error;
  error.name = "selection error";
  error.width = 3.0f;
  error.add(marker->position(frame, 0), marker->position(frame, 1), kSelectionColor);
  port.scene.lines.push_back(std::move(error));
}

}  // namespace

float panel_width(const WindowLayout& layout) { return layout.ui_visible ? kPanelWidth : 0.0f; }

float timeline_height(const WindowLayout& layout, bool has_rollout) {
  if (!layout.ui_visible) return 0.0f;
  return kTimelineHeight + (has_rollout ? kErrorStripHeight : 0.0f);
}

void fit_camera_to_free_area(render::Camera& camera, const Aabb& bounds, const WindowLayout& layout,
                             bool has_rollout, bool split) {
  const double w = layout.width, h = std::max(1, layout.height);
  const double left = panel_width(layout);
  const double bottom = timeline_height(layout, has_rollout);
  const double vw = std::max(1.0, (w - left) / (split ? 2.0 : 1.0)), vh = std::max(1.0, h - bottom);
  camera.fit(bounds, vw / vh);
  if (bounds.empty()) return;
  const double radius = std::max(0.5 * (bounds.max - bounds.min).norm(), 1e-3);
  const double tan_half = std::tan(camera.fov_deg * M_PI / 360.0);
  const double half = std::min(std::atan(tan_half * vh / h), std::atan(tan_half * vw / h));
  camera.distance = 1.1 * radius / std::sin(half);
  camera.pan(-0.5 * left / h, -0.5 * bottom / h);
}

render::ViewSpec rollout_view(const ViewerState& state, bool prediction, bool truth, bool ghost) {
  render::ViewSpec v = state.view();
  v.layers.prediction = prediction;
  v.layers.ground_truth = truth;
  v.layers.ghost = ghost;
  const RolloutDocument* a = state.rollout_document();
  if (v.auto_range && a) {
    float hi = a->max_error();
    if (const RolloutDocument* b = state.compared_rollout()) hi = std::max(hi, b->max_error());
    v.auto_range = false;
    v.range_min = 0.0f;
    v.range_max = std::max(hi, 1e-6f);
  }
  return v;
}

std::vector<Viewport> build_viewports(const ViewerState& state) {
  std::vector<Viewport> out;
  const WindowLayout& layout = state.layout();
  const int w = layout.width, h = layout.height;
  const render::Rect full{0, 0, w, h};
  const render::Camera& camera = state.camera();
  const render::ViewSpec& view = state.view();
  const RolloutDocument* a = state.rollout_document();
  if (!a) {
    if (!state.has_scene()) return out;
    render::ViewSpec v = view;
    // The selection indexes the model trace's level; without it there is nothing to show.
    if (!state.checkpoint().empty() && !state.shown_trace()) v.picked_point = -1;
    v = drawable(state, v);
    Viewport p{
        state.active_data()->frame(state.level_frame(), v), camera, full, level_caption(state), {}};
    // The level's own layer is the selectable one; the rest (all points, edges) are context.
    for (const render::PointLayer& l : p.scene.points) {
      p.layer_sets.push_back(l.pickable && l.series &&
                                     l.series->num_points == state.active_data()->level_size()
                                 ? PickSet::kLevel
                                 : PickSet::kNone);
    }
    out.push_back(std::move(p));
    return out;
  }
  const int f = view.frame;
  const RolloutDocument* compare = state.compared_rollout();
  auto port = [&](const RolloutDocument& doc, const render::ViewSpec& v, const render::Camera& c,
                  render::Rect rect, std::string caption) {
    out.push_back({render::rollout_frame(doc, f, v), c, rect, std::move(caption), {}});
    const std::shared_ptr<render::PointSeries> attribution = state.attribution_series();
    if (&doc == a && attribution && v.layers.prediction) {
      render::add_attribution_layers(out.back().scene, attribution, state.attribution(), f,
                                     doc.point_radius);
    }
  };
  switch (state.rollout_mode()) {
    case RolloutMode::kPrediction:
      port(*a, rollout_view(state, true, false, false), camera, full, "");
      break;
    case RolloutMode::kTruth:
      port(*a, rollout_view(state, false, true, false), camera, full, "");
      break;
    case RolloutMode::kGhost:
      if (compare) {
        port(*a, rollout_view(state, true, false, false), camera, full, "");
        add_prediction_ghost(out.back().scene, *compare, f);
      } else {
        port(*a, rollout_view(state, true, false, true), camera, full, "");
      }
      break;
    case RolloutMode::kSideBySide: {
      const float left = panel_width(layout);
      const double quarter = 0.25 * std::max(1.0f, w - left);
      const int split = static_cast<int>(left + 2.0 * quarter);
      const double hh = std::max(1, h);
      // One camera: each viewport sees it shifted to its own centre.
      render::Camera lc = camera, rc = camera;
      lc.pan(quarter / hh, 0.0);
      rc.pan(-quarter / hh, 0.0);
      const render::Rect lr{0, 0, split, h}, rr{split, 0, w - split, h};
      if (compare) {
        port(*compare, rollout_view(state, true, false, false), lc, lr, compare->path);
        port(*a, rollout_view(state, true, false, false), rc, rr, a->path);
      } else {
        port(*a, rollout_view(state, false, true, false), lc, lr, "truth");
        port(*a, rollout_view(state, true, false, false), rc, rr, "prediction");
      }
      break;
    }
  }
  for (Viewport& p : out) {
    for (const render::PointLayer& l : p.scene.points) {
      p.layer_sets.push_back(rollout_layer_set(state, l));
    }
    add_selection_marker(state, f, p);
  }
  render::RenderScene& last = out.back().scene;
  const size_t before = last.points.size();
  add_scene_layers(state, last);
  out.back().layer_sets.resize(last.points.size(), PickSet::kNone);
  if (last.points.size() > before && out.back().caption.empty()) {
    out.back().caption = level_caption(state);
  }
  return out;
}

PickScene pick_scene(const ViewerState& state, const Viewport& viewport) {
  PickScene out;
  out.scene = viewport.scene;
  out.scene.points.clear();
  out.scene.lines.clear();
  out.scene.boxes.clear();
  // A translucent mesh shows the points behind it, so only opaque ones hide points from a click.
  out.scene.meshes.erase(
      std::remove_if(out.scene.meshes.begin(), out.scene.meshes.end(),
                     [](const render::MeshInstance& m) { return m.opacity < 1.0f; }),
      out.scene.meshes.end());
  for (size_t i = 0; i < viewport.scene.points.size(); ++i) {
    const PickSet set = viewport.layer_sets[i];
    if (set == PickSet::kNone || set == PickSet::kLevel) continue;
    render::PointLayer layer = viewport.scene.points[i];
    layer.opacity = 1.0f;
    layer.pickable = true;
    out.scene.points.push_back(std::move(layer));
    out.sets.push_back(set);
  }
  // Level points: the shown level's points only, so a hit's index is a level point index; with a
  // checkpoint they are the model's once its trace is there.
  const bool levels_drawn = std::find(viewport.layer_sets.begin(), viewport.layer_sets.end(),
                                      PickSet::kLevel) != viewport.layer_sets.end() ||
                            (state.has_rollout() && state.layers().level_points);
  const bool model_levels = state.checkpoint().empty() || state.shown_trace();
  if (levels_drawn && model_levels && state.active_data()) {
    for (render::PointLayer& l : level_pick_scene(state).points) {
      if (!l.pickable) continue;
      out.scene.points.push_back(std::move(l));
      out.sets.push_back(PickSet::kLevel);
    }
  }
  return out;
}

render::RenderScene level_pick_scene(const ViewerState& state) {
  const render::SceneRenderData* data = state.active_data();
  if (!data) throw ValueError("pick", "no scene is loaded");
  render::ViewSpec v = state.view();
  v.layers = render::ViewLayers{};
  v.layers.grid = false;
  v.layers.meshes = false;
  v.layers.prediction = false;
  v.layers.level_points = true;
  v.picked_point = -1;
  return data->frame(state.level_frame(), v);
}

int viewport_at(const std::vector<Viewport>& viewports, int x) {
  std::vector<render::Rect> rects;
  for (const Viewport& p : viewports) rects.push_back(p.rect);
  // Viewports span the window's height: only the column decides.
  const int i = rects.empty() ? -1 : render::find_rect(x, rects.front().y, rects);
  return std::max(i, 0);
}

}  // namespace dynscope::app::viewer
