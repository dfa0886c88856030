// Files panel: open a scene, rollout or trace file; save and open view specs; screenshots.
#include <imgui.h>
#include <imgui_stdlib.h>

#include "app/viewer/panel_util.h"
#include "app/viewer/panels.h"

namespace dynscope::app::viewer {

void draw_files_panel(const ViewerState&, PanelFields& fields, Actions& out) {
  ImGui::PushItemWidth(-90.0f);
  ImGui::InputText("##scene", &fields.open_path);
  ImGui::SameLine();
  if (ImGui::Button("Open", ImVec2(-1, 0))) {
    out.add([path = fields.open_path](ViewerState& s) { s.open_file(path); });
  }
  ImGui::TextColored(kMutedText, "scene, rollout or trace file (.h5)");
  ImGui::InputText("##view", &fields.view_path);
  ImGui::SameLine();
  if (ImGui::Button("Save view", ImVec2(-1, 0))) {
    out.add([path = fields.view_path](ViewerState& s) { s.save_view(path); });
  }
  ImGui::Dummy(ImVec2(0, 0));
  ImGui::SameLine(ImGui::GetContentRegionAvail().x - 82.0f);
  if (ImGui::Button("Open view", ImVec2(-1, 0))) {
    out.add([path = fields.view_path](ViewerState& s) { s.open_view(path); });
  }
  ImGui::InputText("##png", &fields.screenshot_path);
  ImGui::SameLine();
  if (ImGui::Button("Screenshot", ImVec2(-1, 0))) out.screenshot = fields.screenshot_path;
  ImGui::PopItemWidth();
}

}  // namespace dynscope::app::viewer
