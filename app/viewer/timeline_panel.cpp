// Timeline panel: transport buttons, frame slider, speed and loop, and with a rollout the
// per-frame mean error strip with its divergence threshold.
#include <algorithm>
#include <cstdio>

#include "app/viewer/panel_util.h"
#include "app/viewer/panels.h"
#include "app/viewer/viewports.h"

namespace dynscope::app::viewer {
namespace {

void set_frame(Actions& out, int frame) {
  out.add([frame](ViewerState& s) { s.set_frame(frame); });
}

void draw_error_strip(const ViewerState& state, Actions& out) {
  const std::vector<double>& e = state.rollout().rollout.point_error;
  const int frame = state.current_frame();
  const double threshold = state.error_threshold();
  std::vector<float> values(e.begin(), e.end());
  float top = 1e-6f;
  for (float x : values) top = std::max(top, x);
  top = std::max(top, static_cast<float>(threshold) * 1.1f);
  char overlay[96];
  std::snprintf(overlay, sizeof(overlay), "mean point error, frame %d: %.4g", frame,
                e[static_cast<size_t>(frame)]);
  const float width = std::max(100.0f, ImGui::GetContentRegionAvail().x - 330.0f);
  ImGui::PlotHistogram("##error", values.data(), static_cast<int>(values.size()), 0, overlay, 0.0f,
                       top, ImVec2(width, 40.0f));
  const ImVec2 a = ImGui::GetItemRectMin(), b = ImGui::GetItemRectMax();
  if (ImGui::IsItemHovered() && ImGui::IsMouseDown(ImGuiMouseButton_Left)) {
    const float t = (ImGui::GetIO().MousePos.x - a.x) / std::max(1.0f, b.x - a.x);
    set_frame(out, static_cast<int>(t * static_cast<float>(values.size())));
  }
  ImDrawList* draw = ImGui::GetWindowDrawList();
  const float y = b.y - (b.y - a.y) * static_cast<float>(threshold) / top;
  draw->AddLine(ImVec2(a.x, y), ImVec2(b.x, y), IM_COL32(230, 60, 60, 255), 1.5f);
  const float x = a.x + (b.x - a.x) * (frame + 0.5f) / static_cast<float>(values.size());
  draw->AddLine(ImVec2(x, a.y), ImVec2(x, b.y), IM_COL32(255, 255, 255, 200), 1.0f);
  ImGui::SameLine();
  ImGui::BeginGroup();
  double edited = threshold;
  ImGui::SetNextItemWidth(110);
  if (ImGui::InputDouble("threshold", &edited, 0.0, 0.0, "%.4g")) {
    out.add([edited](ViewerState& s) { s.set_error_threshold(std::max(0.0, edited)); });
  }
  if (ImGui::Button("jump to first frame over threshold")) {
    out.add([](ViewerState& s) {
      if (s.jump_to_error_threshold() < 0) {
        throw ValueError("threshold",
                         "no frame's mean error exceeds " + std::to_string(s.error_threshold()));
      }
    });
  }
  ImGui::EndGroup();
}

}  // namespace

void draw_timeline_panel(const ViewerState& state, Actions& out) {
  const ImGuiIO& io = ImGui::GetIO();
  const float height = timeline_height(state.layout(), state.has_rollout());
  ImGui::SetNextWindowPos(ImVec2(0, io.DisplaySize.y - height), ImGuiCond_Always);
  ImGui::SetNextWindowSize(ImVec2(io.DisplaySize.x, height), ImGuiCond_Always);
  const ImGuiWindowFlags flags = ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize |
                                 ImGuiWindowFlags_NoCollapse | ImGuiWindowFlags_NoTitleBar |
                                 ImGuiWindowFlags_NoScrollbar;
  if (ImGui::Begin("Timeline", nullptr, flags)) {
    if (state.num_frames() == 0) {
      ImGui::TextColored(kMutedText, "timeline: no scene");
    } else {
      const int last = state.num_frames() - 1;
      const int current = state.current_frame();
      Timeline t = state.timeline();
      if (ImGui::Button("|<")) set_frame(out, 0);
      ImGui::SameLine();
      if (ImGui::Button("<")) set_frame(out, current - 1);
      ImGui::SameLine();
      bool changed = false;
      if (ImGui::Button(t.playing ? "pause" : "play", ImVec2(48, 0))) {
        t.playing = !t.playing;
        changed = true;
      }
      ImGui::SameLine();
      if (ImGui::Button(">")) set_frame(out, current + 1);
      ImGui::SameLine();
      if (ImGui::Button(">|")) set_frame(out, last);
      ImGui::SameLine();
      int frame = current;
      ImGui::SetNextItemWidth(std::max(100.0f, ImGui::GetContentRegionAvail().x - 330.0f));
      if (ImGui::SliderInt("##frame", &frame, 0, last, "frame %d")) set_frame(out, frame);
      ImGui::SameLine();
      ImGui::Text("t %.3f s", current * state.frame_dt_s());
      ImGui::SameLine();
      ImGui::SetNextItemWidth(90);
      changed |= ImGui::SliderFloat("speed", &t.speed, 0.1f, 4.0f, "%.1fx");
      ImGui::SameLine();
      changed |= ImGui::Checkbox("loop", &t.loop);
      if (changed) out.add([t](ViewerState& s) { s.timeline() = t; });
      if (state.has_rollout()) draw_error_strip(state, out);
    }
    ImGui::TextColored(kMutedText, "space: play/pause   left/right: step   home/end: first/last");
  }
  ImGui::End();
}

}  // namespace dynscope::app::viewer
