// Display panel: which layers the 3D view draws, camera presets.
#include "app/viewer/panel_util.h"
#include "app/viewer/panels.h"

namespace dynscope::app::viewer {

void draw_display_panel(const ViewerState& state, Actions& out) {
  render::ViewLayers l = state.layers();
  bool changed = false;
  changed |= ImGui::Checkbox("meshes", &l.meshes);
  ImGui::SameLine(120);
  changed |= ImGui::Checkbox("grid", &l.grid);
  ImGui::SameLine(220);
  changed |= ImGui::Checkbox("all points", &l.ground_truth);
  changed |= ImGui::Checkbox("level points", &l.level_points);
  ImGui::SameLine(120);
  changed |= ImGui::Checkbox("voxels", &l.voxels);
  ImGui::SameLine(220);
  changed |= ImGui::Checkbox("neighbours", &l.neighborhoods);
  changed |= ImGui::Checkbox("interaction points", &l.interaction_points);
  if (changed) out.add([l](ViewerState& s) { s.layers() = l; });
  const std::string style = state.view().point_style;
  ImGui::SetNextItemWidth(120);
  if (ImGui::BeginCombo("point style", style.c_str())) {
    for (render::PointStyle s :
         {render::PointStyle::kAuto, render::PointStyle::kSpheres, render::PointStyle::kDiscs}) {
      const std::string name = render::point_style_name(s);
      if (ImGui::Selectable(name.c_str(), name == style)) {
        out.add([name](ViewerState& st) { st.set_point_style(name); });
      }
    }
    ImGui::EndCombo();
  }
  ImGui::SameLine();
  ImGui::TextColored(kMutedText, "auto: discs above %d points", render::kDiscPointThreshold);
  ImGui::TextUnformatted("camera");
  for (render::ViewPreset p : {render::ViewPreset::kFront, render::ViewPreset::kSide,
                               render::ViewPreset::kTop, render::ViewPreset::kIso}) {
    ImGui::SameLine();
    if (ImGui::SmallButton(render::preset_name(p))) {
      out.add([p](ViewerState& s) { s.fit_camera(render::preset_name(p)); });
    }
  }
  ImGui::SameLine();
  if (ImGui::SmallButton("fit")) out.add([](ViewerState& s) { s.fit_camera(); });
  ImGui::TextColored(kMutedText, "drag: orbit, right drag: pan, wheel: zoom, click: pick");
}

}  // namespace dynscope::app::viewer
