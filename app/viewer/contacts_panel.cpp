// Contacts panel: target–zone distance over time against the contact threshold, outcomes.
#include <algorithm>
#include <cstdio>

#include "app/viewer/panel_util.h"
#include "app/viewer/panels.h"
#include "engine/rollout/metrics.h"
#include "engine/sim/simulation.h"

namespace dynscope::app::viewer {
namespace {

void draw_rollout_contacts(const ViewerState& state) {
  const RolloutDocument& doc = state.rollout();
  const Rollout& r = doc.rollout;
  const double threshold = kContactThresholdFraction * r.sampling_voxel;
  const std::vector<double>& truth = r.contact_distance_truth;
  const std::vector<double>& pred = r.contact_distance_predicted;
  float top = static_cast<float>(threshold) * 1.2f;
  for (double v : truth) top = std::max(top, static_cast<float>(v));
  for (double v : pred) top = std::max(top, static_cast<float>(v));
  const std::vector<float> t(truth.begin(), truth.end()), p(pred.begin(), pred.end());
  const ImVec2 size(ImGui::GetContentRegionAvail().x, 70.0f);
  const ImVec2 origin = ImGui::GetCursorPos();
  const ImVec4 truth_color(0.3f, 0.8f, 0.4f, 1.0f), pred_color(1.0f, 0.6f, 0.15f, 1.0f);
  ImGui::PushStyleColor(ImGuiCol_PlotLines, truth_color);
  ImGui::PlotLines("##truth", t.data(), static_cast<int>(t.size()), 0, nullptr, 0.0f, top, size);
  ImGui::PopStyleColor();
  const ImVec2 a = ImGui::GetItemRectMin(), b = ImGui::GetItemRectMax();
  // The prediction on the same axes, over the truth (transparent background).
  ImGui::SetCursorPos(origin);
  ImGui::PushStyleColor(ImGuiCol_FrameBg, ImVec4(0, 0, 0, 0));
  ImGui::PushStyleColor(ImGuiCol_PlotLines, pred_color);
  ImGui::PlotLines("##pred", p.data(), static_cast<int>(p.size()), 0, nullptr, 0.0f, top, size);
  ImGui::PopStyleColor(2);
  ImDrawList* draw = ImGui::GetWindowDrawList();
  const float y = b.y - (b.y - a.y) * static_cast<float>(threshold) / top;
  draw->AddLine(ImVec2(a.x, y), ImVec2(b.x, y), IM_COL32(230, 60, 60, 255), 1.0f);
  const int frame = state.current_frame();
  const float x = a.x + (b.x - a.x) * static_cast<float>(frame) /
                            static_cast<float>(std::max<size_t>(1, t.size() - 1));
  draw->AddLine(ImVec2(x, a.y), ImVec2(x, b.y), IM_COL32(255, 255, 255, 160), 1.0f);
  const size_t f = static_cast<size_t>(frame);
  ImGui::TextColored(truth_color, "truth %.4f", truth[f]);
  ImGui::SameLine();
  ImGui::TextColored(pred_color, "predicted %.4f", pred[f]);
  ImGui::SameLine();
  ImGui::TextColored(ImVec4(0.9f, 0.25f, 0.25f, 1.0f), "threshold %.4g", threshold);
  // The engine's one contact rule (engine/rollout/metrics.h) decides both outcomes.
  auto outcome = [&](const std::vector<double>& d) {
    const int first = first_contact_frame(d, threshold);
    return first < 0 ? std::string("no contact") : "contact from frame " + std::to_string(first);
  };
  ImGui::Text("predicted outcome: %s", outcome(pred).c_str());
  ImGui::Text("true outcome:      %s", outcome(truth).c_str());
  // Scenes written by the simulator carry the outcome label (engine/sim kContactLabel).
  if (doc.scene && doc.scene->labels.count(kContactLabel)) {
    {
      const bool labelled = contact_outcome(*doc.scene);
      const bool predicted = contact_predicted(pred, threshold);
      ImGui::Text("labelled outcome:  %s", labelled ? "contact" : "no contact");
      ImGui::SameLine();
      ImGui::TextColored(
          predicted == labelled ? ImVec4(0.3f, 0.8f, 0.4f, 1.0f) : ImVec4(0.9f, 0.25f, 0.25f, 1.0f),
          predicted == labelled ? "(prediction agrees)" : "(prediction disagrees)");
    }
  }
  ImGui::TextColored(kMutedText, "target-zone minimum point distance: truth and prediction");
}

}  // namespace

void draw_contacts_panel(const ViewerState& state, Actions&) {
  const SceneDocument& doc = state.document();
  const Scene& scene = doc.scene;
  const std::vector<double>& d = doc.contact_distance;
  const int frame = state.current_frame();
  if (state.has_rollout() && state.rollout().rollout.has_contact()) {
    draw_rollout_contacts(state);
  } else if (d.empty()) {
    ImGui::TextWrapped("This scene has no target and zone object (no contact timeline).");
  } else {
    std::vector<float> values(d.begin(), d.end());
    const float top = std::max(1e-3f, *std::max_element(values.begin(), values.end()));
    char overlay[64];
    const int f = std::min(frame, static_cast<int>(d.size()) - 1);
    std::snprintf(overlay, sizeof(overlay), "frame %d: %.3f", f, d[f]);
    ImGui::PlotLines("##dist", values.data(), static_cast<int>(values.size()), 0, overlay, 0.0f,
                     top, ImVec2(-1, 60));
    ImGui::TextColored(kMutedText, "target-zone minimum point distance over time");
  }
  for (const auto& [name, values] : scene.labels) {
    const auto first = std::find_if(values.begin(), values.end(), [](double v) { return v > 0.5; });
    ImGui::Text("%s: %s", name.c_str(),
                frame < static_cast<int>(values.size()) && values[frame] > 0.5 ? "yes" : "no");
    ImGui::SameLine();
    if (first == values.end()) {
      ImGui::TextColored(kMutedText, "(never)");
    } else {
      ImGui::TextColored(kMutedText, "(first at frame %d)",
                         static_cast<int>(first - values.begin()));
    }
  }
}

}  // namespace dynscope::app::viewer
