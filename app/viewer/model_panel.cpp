// Model panel: the checkpoint in use, its trace, rollouts of one or two checkpoints.
#include <imgui.h>
#include <imgui_stdlib.h>

#include <cstdio>

#include "app/viewer/panel_util.h"
#include "app/viewer/panels.h"

namespace dynscope::app::viewer {

void draw_model_panel(const ViewerState& state, PanelFields& fields, Actions& out) {
  ImGui::PushItemWidth(-90.0f);
  ImGui::InputText("##checkpoint", &fields.checkpoint);
  ImGui::SameLine();
  if (ImGui::Button(state.checkpoint().empty() ? "Use" : "Change", ImVec2(-1, 0))) {
    out.add([path = fields.checkpoint](ViewerState& s) { s.set_checkpoint(path); });
  }
  ImGui::PopItemWidth();
  ImGui::TextColored(kMutedText, "checkpoint (.pt): traces drive levels and inspector");
  const ModelTrace* held = state.held_trace();
  if (!state.checkpoint().empty()) {
    if (state.trace_job_frame() >= 0) {
      ImGui::Text("capturing model trace at frame %d...", state.trace_job_frame());
    } else if (state.shown_trace()) {
      ImGui::Text("model trace: frame %d, level %d", held->frame, state.trace_level());
    }
    ImGui::PushItemWidth(-90.0f);
    ImGui::InputText("##compare", &fields.compare);
    ImGui::PopItemWidth();
    ImGui::SameLine();
    if (ImGui::Button("Roll out", ImVec2(-1, 0))) {
      out.add([compare = fields.compare](ViewerState& s) { s.start_rollouts(compare); });
    }
    ImGui::TextColored(kMutedText, "roll the checkpoint out (optional: a second one to compare)");
  } else if (state.trace_from_file() && held) {
    ImGui::Text("trace file: frame %d (%s)", held->frame, file_name(held->checkpoint_path).c_str());
  }
  if (const auto* job = state.rollout_job()) {
    char label[64];
    std::snprintf(label, sizeof(label), "%s %.0f%%", job->label().c_str(),
                  100.0f * job->fraction());
    ImGui::ProgressBar(job->fraction(), ImVec2(-1, 0), label);
    ImGui::SameLine();
    if (ImGui::SmallButton("cancel")) out.add([](ViewerState& s) { s.cancel_jobs(); });
  }
}

}  // namespace dynscope::app::viewer
