// ImGuiSession: the viewer's ImGui context and style.
#include "app/viewer/platform.h"

#include <imgui.h>

namespace dynscope::app::viewer {

ImGuiSession::ImGuiSession() {
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGuiIO& io = ImGui::GetIO();
  // No imgui.ini: the panel layout is fixed by the viewer, so screenshots do not depend on it.
  io.IniFilename = nullptr;
  io.LogFilename = nullptr;
  ImGui::StyleColorsDark();
  ImGuiStyle& style = ImGui::GetStyle();
  style.WindowRounding = 0.0f;
  style.FrameRounding = 2.0f;
  style.WindowBorderSize = 0.0f;
  style.Colors[ImGuiCol_WindowBg].w = 0.92f;
}

ImGuiSession::~ImGuiSession() { ImGui::DestroyContext(); }

}  // namespace dynscope::app::viewer
