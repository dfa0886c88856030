// Helpers shared by the panel files.
#include "app/viewer/panel_util.h"

#include <cstdio>

namespace dynscope::app::viewer {

std::string format_vec(const Vec3& v, const char* format) {
  char x[32], y[32], z[32];
  std::snprintf(x, sizeof(x), format, v.x());
  std::snprintf(y, sizeof(y), format, v.y());
  std::snprintf(z, sizeof(z), format, v.z());
  return std::string("(") + x + ", " + y + ", " + z + ")";
}

std::string file_name(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

void draw_colorbar(const std::string& colormap, float lo, float hi) {
  const ImVec2 size(ImGui::GetContentRegionAvail().x, 12.0f);
  const ImVec2 p = ImGui::GetCursorScreenPos();
  ImDrawList* draw = ImGui::GetWindowDrawList();
  constexpr int kSteps = 32;
  for (int i = 0; i < kSteps; ++i) {
    const render::Color a = render::colormap(colormap, static_cast<float>(i) / kSteps);
    const render::Color b = render::colormap(colormap, static_cast<float>(i + 1) / kSteps);
    const float x0 = p.x + size.x * i / kSteps, x1 = p.x + size.x * (i + 1) / kSteps;
    draw->AddRectFilledMultiColor(ImVec2(x0, p.y), ImVec2(x1, p.y + size.y),
                                  ImGui::GetColorU32(to_imvec(a)), ImGui::GetColorU32(to_imvec(b)),
                                  ImGui::GetColorU32(to_imvec(b)), ImGui::GetColorU32(to_imvec(a)));
  }
  ImGui::Dummy(size);
  ImGui::Text("%.4g", lo);
  char text[32];
  std::snprintf(text, sizeof(text), "%.4g", hi);
  ImGui::SameLine(ImGui::GetContentRegionAvail().x - ImGui::CalcTextSize(text).x);
  ImGui::TextUnformatted(text);
  ImGui::SameLine(0.35f * ImGui::GetContentRegionAvail().x);
  ImGui::TextColored(kMutedText, "|pred - truth| (%s)", colormap.c_str());
}

}  // namespace dynscope::app::viewer
