// Rollout panel: display mode, error colours and range, the frame's mean error.
#include "app/viewer/panel_util.h"
#include "app/viewer/panels.h"
#include "app/viewer/viewports.h"

namespace dynscope::app::viewer {

void draw_rollout_panel(const ViewerState& state, Actions& out) {
  const RolloutDocument& doc = state.rollout();
  const RolloutDocument* compare = state.compared_rollout();
  const Rollout& r = doc.rollout;
  ImGui::TextWrapped("%s", doc.path.c_str());
  ImGui::TextColored(kMutedText, "%d frames (%d observed), %lld points, voxel %.3g", r.num_frames(),
                     r.observed_frames, static_cast<long long>(r.num_points()), r.sampling_voxel);
  if (!r.checkpoint_path.empty()) {
    ImGui::TextColored(kMutedText, "checkpoint %s", file_name(r.checkpoint_path).c_str());
  }
  if (!doc.scene) ImGui::TextColored(kMutedText, "scene file not found: no meshes");
  int mode = static_cast<int>(state.rollout_mode());
  ImGui::RadioButton("prediction", &mode, static_cast<int>(RolloutMode::kPrediction));
  ImGui::SameLine();
  ImGui::RadioButton("truth", &mode, static_cast<int>(RolloutMode::kTruth));
  ImGui::SameLine();
  ImGui::RadioButton(compare ? "ghost (compared)" : "ghost", &mode,
                     static_cast<int>(RolloutMode::kGhost));
  ImGui::RadioButton(
      compare ? "side by side (compared | shown)" : "side by side (truth | prediction)", &mode,
      static_cast<int>(RolloutMode::kSideBySide));
  if (mode != static_cast<int>(state.rollout_mode())) {
    out.add([mode](ViewerState& s) { s.set_rollout_mode(static_cast<RolloutMode>(mode)); });
  }
  if (compare) {
    ImGui::TextColored(kMutedText, "compared: %s (compared set)", compare->path.c_str());
  }
  const render::ViewSpec& view = state.view();
  bool error = view.layers.error, automatic = view.auto_range;
  if (ImGui::Checkbox("error colours", &error)) {
    out.add([error](ViewerState& s) { s.layers().error = error; });
  }
  ImGui::SameLine();
  float lo = view.range_min, hi = view.range_max;
  bool range_changed = ImGui::Checkbox("auto range", &automatic);
  if (!view.auto_range) {
    ImGui::SetNextItemWidth(200);
    range_changed |= ImGui::DragFloatRange2("range", &lo, &hi, 0.001f, 0.0f, 1e3f, "%.4f", "%.4f");
  }
  if (range_changed) {
    out.add([automatic, lo, hi](ViewerState& s) { s.set_error_range(automatic, lo, hi); });
  }
  const render::ViewSpec v = rollout_view(state, true, false, false);
  if (view.layers.error) draw_colorbar(view.colormap, v.range_min, v.range_max);
  const int f = view.frame;
  ImGui::Text("frame %d (%s): mean error %.4g", f, f < r.observed_frames ? "observed" : "predicted",
              r.point_error[static_cast<size_t>(f)]);
  if (compare) {
    ImGui::Text("compared: mean error %.4g", compare->rollout.point_error[static_cast<size_t>(f)]);
  }
}

}  // namespace dynscope::app::viewer
