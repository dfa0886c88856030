// ViewerState's view: camera fitting, view specs, point style, colour range and playback.
#include <algorithm>

#include "app/viewer/viewer_state.h"
#include "app/viewer/viewports.h"
#include "engine/core/error.h"
#include "render/view_spec.h"

namespace dynscope::app::viewer {

const char* pick_set_name(PickSet set) {
  switch (set) {
    case PickSet::kLevel:
      return "level points";
    case PickSet::kPrediction:
      return "prediction";
    case PickSet::kTruth:
      return "truth";
    case PickSet::kCompared:
      return "compared prediction";
    case PickSet::kNone:
      break;
  }
  return "";
}

void ViewerState::set_view(const render::ViewSpec& view) {
  view.validate();
  if (num_frames() > 0 && view.frame >= num_frames()) {
    throw ValueError("frame", std::to_string(view.frame) + " is outside the " +
                                  std::to_string(num_frames()) + " frames shown");
  }
  const render::ViewSpec previous = view_;
  view_ = view;
  // Voxel or point size may differ: rebuild the level data from scratch.
  data_stale_ = true;
  try {
    ensure_render_data();
    if (doc_ && (view_.picked_point != view.picked_point ||
                 view_.picked_point >= active_data()->level_size())) {
      throw ValueError("picked_point",
                       std::to_string(view_.picked_point) + " is outside the level's points");
    }
  } catch (...) {
    view_ = previous;
    data_stale_ = true;
    ensure_render_data();
    throw;
  }
  if (view_.camera.fit) fit_camera();
  if (view_.picked_point >= 0) show_panel(Panel::kInspector);
  if (view_.level > 0 || view_.layers.voxels) show_panel(Panel::kLevels);
}

void ViewerState::open_view(const std::string& path) { set_view(render::load_view_spec(path)); }

render::ViewSpec ViewerState::current_view() const {
  render::ViewSpec v = view_;
  v.width = layout_.width;
  v.height = layout_.height;
  v.camera.fit = false;
  v.camera.preset.clear();
  return v;
}

void ViewerState::save_view(const std::string& path) const {
  render::save_view_spec(current_view(), path);
}

void ViewerState::set_point_style(const std::string& style) {
  render::parse_point_style(style);
  view_.point_style = style;
}

void ViewerState::set_error_range(bool automatic, float lo, float hi) {
  view_.auto_range = automatic;
  view_.range_min = lo;
  view_.range_max = std::max(hi, lo + 1e-6f);
}

void ViewerState::fit_camera(const std::string& preset) {
  if (!preset.empty()) view_.camera.preset = preset;
  if (!doc_ && !rollout_) return;
  render::Camera& camera = view_.camera.camera;
  if (!view_.camera.preset.empty()) camera.set_preset(render::parse_preset(view_.camera.preset));
  Aabb bounds;
  if (rollout_) {
    bounds = rollout_->bounds;
    if (compare_) bounds.extend(compare_->bounds);
  } else {
    bounds = doc_->data->bounds(0, doc_->scene.num_frames() - 1);
  }
  fit_camera_to_free_area(camera, bounds, layout_, rollout_ != nullptr,
                          rollout_ && rollout_mode_ == RolloutMode::kSideBySide);
  view_.camera.fit = false;
  view_.camera.preset.clear();
}

void ViewerState::advance_playback(float dt_s) {
  if (num_frames() == 0 || !timeline_.playing) return;
  const int last = num_frames() - 1;
  const double frame_s = frame_dt_s();
  timeline_.accumulated_s += dt_s * timeline_.speed;
  while (timeline_.accumulated_s >= frame_s) {
    timeline_.accumulated_s -= frame_s;
    if (view_.frame < last) {
      ++view_.frame;
    } else if (timeline_.loop) {
      view_.frame = 0;
    } else {
      timeline_.playing = false;
      timeline_.accumulated_s = 0.0;
      break;
    }
  }
}

}  // namespace dynscope::app::viewer
