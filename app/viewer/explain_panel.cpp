// Explain panel: where the shown rollout diverges, the object pairs the model saw in contact
// there, and which neighbour lists made the chosen object or point go wrong (background job).
#include <algorithm>
#include <cstdio>
#include <string>

#include "app/viewer/panel_util.h"
#include "app/viewer/panels.h"
#include "engine/rollout/explain_report.h"
#include "render/colormap.h"

namespace dynscope::app::viewer {
namespace {

// TextWrapped in the muted colour.
template <typename... Args>
void muted_wrapped(const char* format, Args... args) {
  ImGui::PushStyleColor(ImGuiCol_Text, kMutedText);
  ImGui::TextWrapped(format, args...);
  ImGui::PopStyleColor();
}

// Every object's error curve on one plot (object colours), with the threshold line and the
// divergence and current frames marked.
void draw_error_curves(const Divergence& d, int frame) {
  const ObjectErrorCurves& c = d.curves;
  if (c.objects.empty() || c.errors.front().empty()) return;
  float top = 1e-6f;
  for (const std::vector<double>& e : c.errors) {
    for (double v : e) top = std::max(top, static_cast<float>(v));
  }
  const ImVec2 size(ImGui::GetContentRegionAvail().x, 60.0f);
  const ImVec2 origin = ImGui::GetCursorPos();
  for (size_t o = 0; o < c.objects.size(); ++o) {
    const std::vector<float> values(c.errors[o].begin(), c.errors[o].end());
    ImGui::SetCursorPos(origin);
    if (o > 0) ImGui::PushStyleColor(ImGuiCol_FrameBg, ImVec4(0, 0, 0, 0));
    ImGui::PushStyleColor(ImGuiCol_PlotLines, to_imvec(render::categorical_color(c.objects[o])));
    const std::string id = "##error" + std::to_string(o);
    ImGui::PlotLines(id.c_str(), values.data(), static_cast<int>(values.size()), 0, nullptr, 0.0f,
                     top, size);
    ImGui::PopStyleColor(o > 0 ? 2 : 1);
  }
  const ImVec2 a = ImGui::GetItemRectMin(), b = ImGui::GetItemRectMax();
  ImDrawList* draw = ImGui::GetWindowDrawList();
  const auto frames = static_cast<float>(std::max<size_t>(1, c.errors.front().size() - 1));
  auto x_of = [&](int f) { return a.x + (b.x - a.x) * static_cast<float>(f) / frames; };
  if (d.found()) {
    const float x = x_of(d.frame + 1);
    draw->AddLine(ImVec2(x, a.y), ImVec2(x, b.y), IM_COL32(230, 60, 60, 255), 1.0f);
  }
  draw->AddLine(ImVec2(x_of(frame), a.y), ImVec2(x_of(frame), b.y), IM_COL32(255, 255, 255, 160),
                1.0f);
  muted_wrapped("per-object mean error (object colours); red: the divergence");
}

void draw_divergence(const ViewerState& state, const Divergence& d, const ObjectNames& names,
                     Actions& out) {
  if (d.found()) {
    ImGui::TextWrapped("Diverges at pass %d -> frame %d: %s's error grows %.4g per frame.", d.frame,
                       d.frame + 1, names(d.object).c_str(), d.growth);
  } else {
    ImGui::TextWrapped("No divergence: no object's error grows above the threshold.");
  }
  muted_wrapped("threshold %.4g: %s", d.threshold, d.threshold_rule.c_str());
  draw_error_curves(d, state.current_frame());
  for (const ObjectDivergence& o : d.objects) {
    if (o.frame < 0) continue;
    char label[160];
    std::snprintf(label, sizeof(label), "%s: first at pass %d (grows %.4g)##div%d",
                  names(o.object).c_str(), o.frame, o.growth, o.object);
    if (ImGui::Selectable(label, state.current_frame() == o.frame)) {
      const int f = o.frame;
      out.add([f](ViewerState& s) { s.set_frame(f); });
    }
  }
  if (!d.found()) return;
  ImGui::TextWrapped("In contact at pass %d (the model's relational lists):", d.frame);
  if (d.contacts.empty()) ImGui::TextColored(kMutedText, "  none");
  for (const ContactPair& c : d.contacts) {
    char label[160];
    std::snprintf(label, sizeof(label), "  %s - %s (%d edges)##pair%d_%d", names(c.a).c_str(),
                  names(c.b).c_str(), c.edges, c.a, c.b);
    if (ImGui::Selectable(label)) {
      const int frame = d.frame;
      const int32_t a = c.a, b = c.b;
      out.add([frame, a, b](ViewerState& s) { s.inspect_pair(frame, a, b); });
    }
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Jump there with the inspector on this pair");
  }
}

void draw_contributors(const ViewerState& state, const Explanation& e, const ObjectNames& names,
                       Actions& out) {
  ImGui::Separator();
  ImGui::TextWrapped("%s at pass %d (predicting frame %d): error %.4g (%+.4g per frame)",
                     explained_subject(e, names).c_str(), e.frame, e.frame + 1, e.error,
                     e.error_growth);
  muted_wrapped("attributed %s %.4g; sum |dE/dg| over all edges %.3g",
                explain_target_name(e.target), e.value, e.edge_total);
  bool colors = state.attribution_colors();
  if (ImGui::Checkbox("colour points by share", &colors)) {
    out.add([colors](ViewerState& s) { s.set_attribution_colors(colors); });
  }
  if (e.contributors.empty()) {
    ImGui::TextColored(kMutedText, "No neighbour edge reaches it.");
    return;
  }
  const ImGuiTableFlags flags =
      ImGuiTableFlags_RowBg | ImGuiTableFlags_BordersInnerV | ImGuiTableFlags_SizingStretchProp;
  if (!ImGui::BeginTable("contributors", 4, flags)) return;
  ImGui::TableSetupColumn("list");
  ImGui::TableSetupColumn("level");
  ImGui::TableSetupColumn("object");
  ImGui::TableSetupColumn("share");
  ImGui::TableHeadersRow();
  const size_t rows = std::min<size_t>(e.contributors.size(), 12);
  for (size_t i = 0; i < rows; ++i) {
    const Contributor& c = e.contributors[i];
    ImGui::TableNextRow();
    ImGui::TableNextColumn();
    ImGui::TextUnformatted(c.list.c_str());
    ImGui::TableNextColumn();
    ImGui::Text("%d", c.level);
    ImGui::TableNextColumn();
    ImGui::TextColored(to_imvec(render::categorical_color(c.object)), "%s",
                       names(c.object).c_str());
    ImGui::TableNextColumn();
    char text[32];
    std::snprintf(text, sizeof(text), "%.1f %%", 100.0 * c.share);
    ImGui::ProgressBar(static_cast<float>(c.share), ImVec2(-1, 0), text);
    if (ImGui::IsItemHovered()) {
      ImGui::SetTooltip("%d edges, effect %+.3g (> 0: pushed the %s up)", c.edges, c.effect,
                        explain_target_name(e.target));
    }
  }
  ImGui::EndTable();
  if (rows < e.contributors.size()) {
    ImGui::TextColored(kMutedText, "%zu more groups", e.contributors.size() - rows);
  }
}

}  // namespace

void draw_explain_panel(const ViewerState& state, PanelFields& fields, Actions& out) {
  const RolloutDocument& doc = state.rollout();
  const Rollout& r = doc.rollout;
  if (state.checkpoint().empty()) {
    ImGui::TextWrapped("Choose the checkpoint that made this rollout (Model panel) to explain it.");
    return;
  }
  const ObjectNames names = object_names(r, doc.scene ? &*doc.scene : nullptr);
  muted_wrapped(
      "Which neighbour lists made a prediction go wrong: gradient x input over the "
      "edges of every list, on the rollout's own frames.");
  ImGui::SetNextItemWidth(140);
  ImGui::Combo("attribute", &fields.explain_target, "error\0acceleration\0");
  const auto target = static_cast<ExplainTarget>(fields.explain_target);
  const bool running = state.explain_job() != nullptr;
  if (running) ImGui::BeginDisabled();
  if (ImGui::Button("Explain divergence")) {
    out.add([target](ViewerState& s) { s.start_explain(-1, -1, -1, target); });
  }
  const int frame = state.current_frame();
  const PassRange passes = rollout_passes(r);
  const bool pass_here = frame >= passes.first && frame <= passes.last;
  if (!pass_here) ImGui::BeginDisabled();
  if (ImGui::Button("This pass")) {
    out.add([frame, target](ViewerState& s) { s.start_explain(frame, -1, -1, target); });
  }
  const Selection pick = state.selection();
  const bool rollout_point = pick.set == PickSet::kPrediction || pick.set == PickSet::kTruth;
  ImGui::SameLine();
  if (!rollout_point) ImGui::BeginDisabled();
  if (ImGui::Button("Selected point")) {
    const int point = pick.point;
    out.add([frame, point, target](ViewerState& s) { s.start_explain(frame, -1, point, target); });
  }
  if (!rollout_point) ImGui::EndDisabled();
  if (!pass_here) ImGui::EndDisabled();
  if (running) {
    ImGui::EndDisabled();
    ImGui::ProgressBar(state.explain_job()->fraction(), ImVec2(-1, 0), "explaining...");
  }
  if (!pass_here) {
    ImGui::TextColored(kMutedText, "passes %d..%d predicted frames %d..%d", passes.first,
                       passes.last, passes.first + 1, passes.last + 1);
  }
  const RolloutExplanation* x = state.explanation();
  if (!x) return;
  draw_divergence(state, x->divergence, names, out);
  draw_contributors(state, x->explanation, names, out);
}

}  // namespace dynscope::app::viewer
