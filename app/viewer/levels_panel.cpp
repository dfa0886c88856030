// Levels panel: the U-Net level shown, its points and voxels, and the hierarchy's counts.
#include "app/viewer/panel_util.h"
#include "app/viewer/panels.h"
#include "render/scene_adapter.h"

namespace dynscope::app::viewer {

void draw_levels_panel(const ViewerState& state, Actions& out) {
  const render::SceneRenderData& data = *state.active_data();
  const render::ViewSpec& view = state.view();
  int level = view.level;
  ImGui::SetNextItemWidth(150);
  if (ImGui::SliderInt("level", &level, 0, state.num_levels() - 1)) {
    out.add([level](ViewerState& s) { s.set_level(level); });
  }
  bool points = view.layers.level_points, voxels = view.layers.voxels;
  ImGui::SameLine();
  if (ImGui::Checkbox("points", &points)) {
    out.add([points](ViewerState& s) { s.layers().level_points = points; });
  }
  ImGui::SameLine();
  if (ImGui::Checkbox("voxels", &voxels)) {
    out.add([voxels](ViewerState& s) { s.layers().voxels = voxels; });
  }
  ImGui::Text("shown: %d points, voxel %.3g, radius %.3g", data.level_size(), data.level_voxel(),
              data.level_radius());
  const SceneDocument& doc = state.document();
  if (view.frame >= doc.scene.num_frames()) return;
  const std::vector<LevelCount> counts = state.level_counts();
  if (const ModelTrace* trace = state.shown_trace()) {
    if (is_level_view(*trace)) {
      ImGui::TextColored(kMutedText, "the model's hierarchy (%s input, no checkpoint) at frame %d",
                         to_string(render::level_view_config(doc.scene, view).input).c_str(),
                         trace->frame);
    } else {
      ImGui::TextColored(kMutedText, "the model's own hierarchy (trace) at frame %d", trace->frame);
    }
  } else if (!state.checkpoint().empty()) {
    if (state.trace_job_frame() >= 0) {
      ImGui::TextColored(kMutedText, "capturing the model's trace...");
    }
  } else {
    out.add([](ViewerState& s) { s.request_level_view(); });  // the counts below, next frame
  }
  const Scene& scene = doc.scene;
  const int columns = 3 + static_cast<int>(scene.objects.size());
  const ImGuiTableFlags flags =
      ImGuiTableFlags_Borders | ImGuiTableFlags_RowBg | ImGuiTableFlags_SizingFixedFit;
  if (!ImGui::BeginTable("levels", columns, flags)) return;
  ImGui::TableSetupColumn("lvl");
  ImGui::TableSetupColumn("voxel");
  ImGui::TableSetupColumn("points");
  for (const Object& o : scene.objects) {
    ImGui::TableSetupColumn(("obj " + std::to_string(o.id)).c_str());
  }
  ImGui::TableHeadersRow();
  for (const LevelCount& c : counts) {
    ImGui::TableNextRow();
    if (c.level == view.level) {
      ImGui::TableSetBgColor(ImGuiTableBgTarget_RowBg1, IM_COL32(60, 90, 140, 160));
    }
    ImGui::TableNextColumn();
    ImGui::Text("%d", c.level);
    ImGui::TableNextColumn();
    if (c.level == 0) {
      ImGui::TextUnformatted("-");
    } else {
      ImGui::Text("%.3g", c.voxel);
    }
    ImGui::TableNextColumn();
    ImGui::Text("%d", c.points);
    for (const Object& o : scene.objects) {
      ImGui::TableNextColumn();
      const auto it = c.per_object.find(o.id);
      ImGui::Text("%d", it == c.per_object.end() ? 0 : it->second);
    }
  }
  ImGui::EndTable();
}

}  // namespace dynscope::app::viewer
