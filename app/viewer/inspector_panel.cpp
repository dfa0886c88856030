// Inspector panel (the document's pick UI): the selected point, its object kNN and relational
// neighbourhoods with the learned filter weights, feature norms and the mesh input's pairs.
#include <algorithm>
#include <cfloat>

#include "app/viewer/panel_util.h"
#include "app/viewer/panels.h"
#include "engine/model/hierarchy.h"
#include "engine/model/model_config.h"

namespace dynscope::app::viewer {
namespace {

void draw_trace_features(const ModelTrace& trace, int level, int picked) {
  std::vector<float> norms;
  std::string names;
  for (const TraceFeatures& f : trace.features) {
    if (f.level != level || picked >= static_cast<int>(f.norms.size())) continue;
    norms.push_back(static_cast<float>(f.norms[static_cast<size_t>(picked)]));
    names += (names.empty() ? "" : ", ") + f.block;
  }
  if (norms.empty()) return;
  ImGui::TextColored(kMutedText, "feature norms after: %s", names.c_str());
  ImGui::PlotHistogram("##features", norms.data(), static_cast<int>(norms.size()), 0,
                       "|feature| per block", 0.0f, FLT_MAX, ImVec2(-1, 40));
}

void draw_trace_mesh(const ViewerState& state, const ModelTrace& trace, Actions& out) {
  int pairs = 0;
  for (const TraceList& l : trace.mesh.lists) {
    if (l.name == mesh_list_name(MeshList::kSenders)) pairs = static_cast<int>(l.mask.count());
  }
  double threshold = 0.0;
  try {
    threshold = ModelConfig::from_json(trace.model_config, "trace").interaction_threshold;
  } catch (const Error&) {
    threshold = 0.0;  // an unreadable config only hides the number
  }
  ImGui::Text("mesh input: %lld interaction points, %d sender pairs",
              static_cast<long long>(trace.mesh.points.rows()), pairs);
  ImGui::Text("interaction threshold %.4g", threshold);
  ImGui::SameLine();
  bool show = state.layers().interaction_points;
  if (ImGui::Checkbox("show", &show)) {
    out.add([show](ViewerState& s) { s.layers().interaction_points = show; });
  }
}

// How the picked point's lists, read from the rollout's prediction, differ from those the same
// model builds from the ground truth at the frame (level 0: the same points in both).
void draw_input_difference(const ModelTrace& predicted, const ModelTrace& truth, int level,
                           int point) {
  ImGui::TextColored(kMutedText, "lists from the prediction vs from the ground truth:");
  if (level != 0) {
    ImGui::TextWrapped("(level %d has other points in each; compare at level 0)", level);
    return;
  }
  auto line = [](const char* name, const ListDifference& d) {
    auto join = [](const std::vector<int>& v) {
      std::string s;
      for (int i : v) s += (s.empty() ? "" : " ") + std::to_string(i);
      return s.empty() ? std::string("-") : s;
    };
    if (d.only_a.empty() && d.only_b.empty()) {
      ImGui::Text("%s: the same", name);
      return;
    }
    ImGui::TextWrapped("%s: only with the prediction %s; only with the truth %s", name,
                       join(d.only_a).c_str(), join(d.only_b).c_str());
  };
  line("object kNN", neighbor_difference(predicted, truth, LevelList::kSame, point));
  line("relational", neighbor_difference(predicted, truth, LevelList::kRelational, point));
}

// One neighbour list as a table (point, object, distance, |h|) and the filter as bars.
void neighbour_table(const char* id, const std::vector<NeighborEntry>& list, const ImVec4& color,
                     bool traced) {
  const ImGuiTableFlags flags = ImGuiTableFlags_Borders | ImGuiTableFlags_RowBg |
                                ImGuiTableFlags_ScrollY | ImGuiTableFlags_SizingStretchSame;
  const float rows = static_cast<float>(std::min<size_t>(list.size(), 5) + 1);
  const int columns = traced ? 4 : 3;
  if (list.empty() || !ImGui::BeginTable(id, columns, flags, ImVec2(0, rows * 19.0f + 4.0f))) {
    return;
  }
  ImGui::TableSetupScrollFreeze(0, 1);
  ImGui::TableSetupColumn("point");
  ImGui::TableSetupColumn("object");
  ImGui::TableSetupColumn("distance");
  if (traced) ImGui::TableSetupColumn("|h|");
  ImGui::TableHeadersRow();
  for (const NeighborEntry& e : list) {
    ImGui::TableNextRow();
    ImGui::TableNextColumn();
    ImGui::TextColored(color, "%d", e.point);
    ImGui::TableNextColumn();
    ImGui::Text("%d", e.object_id);
    ImGui::TableNextColumn();
    ImGui::Text("%.4f", e.distance);
    if (traced) {
      ImGui::TableNextColumn();
      if (e.weight >= 0.0) {
        ImGui::Text("%.4f", e.weight);
      } else {
        ImGui::TextColored(kMutedText, "-");
      }
    }
  }
  ImGui::EndTable();
  // The learned filter h(p_k - p_0) as bars, one per neighbour in list order.
  std::vector<float> bars;
  for (const NeighborEntry& e : list) {
    if (e.weight >= 0.0) bars.push_back(static_cast<float>(e.weight));
  }
  if (!bars.empty()) {
    ImGui::PushStyleColor(ImGuiCol_PlotHistogram, color);
    ImGui::PlotHistogram((std::string("##h") + id).c_str(), bars.data(),
                         static_cast<int>(bars.size()), 0, "|h(p_k - p_0)|", 0.0f, FLT_MAX,
                         ImVec2(-1, 40));
    ImGui::PopStyleColor();
  }
}

// A picked rollout point: which set and frame, where both sets have it, and the error.
void draw_rollout_point(const ViewerState& state, const Selection& picked, Actions& out) {
  const RolloutDocument& doc =
      picked.set == PickSet::kCompared ? *state.compared_rollout() : state.rollout();
  const Rollout& r = doc.rollout;
  const int f = std::min(state.current_frame(), doc.num_frames() - 1);
  const auto i = static_cast<Eigen::Index>(picked.point);
  ImGui::Text("point %d of the %s, frame %d", picked.point, pick_set_name(picked.set), f);
  ImGui::SameLine();
  if (ImGui::SmallButton("clear")) {
    out.add([](ViewerState& s) { s.select_point(-1); });
    return;
  }
  if (picked.frame != f) {
    ImGui::TextColored(kMutedText, "picked at frame %d; points keep their identity", picked.frame);
  }
  const int32_t id = r.object_ids[static_cast<size_t>(i)];
  std::string name;
  if (doc.scene && doc.scene->object_index(id) >= 0) {
    name = doc.scene->objects[static_cast<size_t>(doc.scene->object_index(id))].name;
  }
  const Vec3 predicted = r.predicted[static_cast<size_t>(f)].row(i).transpose();
  const Vec3 truth = r.truth[static_cast<size_t>(f)].row(i).transpose();
  ImGui::Text("object    %d %s", id, name.c_str());
  ImGui::Text("predicted %s", format_vec(predicted).c_str());
  ImGui::Text("truth     %s", format_vec(truth).c_str());
  ImGui::Text("error     %.4f", (predicted - truth).norm());
  if (f < r.observed_frames) {
    ImGui::TextColored(kMutedText, "frame %d is observed: the prediction is the truth", f);
  }
}

}  // namespace

void draw_inspector_panel(const ViewerState& state, Actions& out) {
  const Selection picked = state.selection();
  if (picked.set == PickSet::kPrediction || picked.set == PickSet::kTruth ||
      picked.set == PickSet::kCompared) {
    draw_rollout_point(state, picked, out);
    return;
  }
  const ModelTrace* trace = state.shown_trace();
  const render::ViewSpec& view = state.view();
  const int frame = state.level_frame();
  if (state.has_rollout() && !state.checkpoint().empty() && !state.trace_from_file()) {
    int input = state.trace_input() == TraceInput::kPrediction ? 0 : 1;
    ImGui::TextUnformatted("model input:");
    ImGui::SameLine();
    if (ImGui::RadioButton("its prediction", &input, 0)) {
      out.add([](ViewerState& s) { s.set_trace_input(TraceInput::kPrediction); });
    }
    ImGui::SameLine();
    if (ImGui::RadioButton("ground truth", &input, 1)) {
      out.add([](ViewerState& s) { s.set_trace_input(TraceInput::kTruth); });
    }
  }
  if (!state.checkpoint().empty() && state.trace_frame() > view.frame) {
    ImGui::TextWrapped(
        "Frame %d is observed: the model reads frames t-2..t, so the inspector shows its trace "
        "at frame %d, the first it can trace.",
        view.frame, state.trace_frame());
  } else if (!state.checkpoint().empty() && state.trace_frame() < view.frame) {
    ImGui::TextWrapped(
        "Frame %d is the last: the inspector shows the pass at frame %d, which "
        "predicted it.",
        view.frame, state.trace_frame());
  }
  if (!state.checkpoint().empty() && !trace) {
    ImGui::TextWrapped("Capturing the model's trace at frame %d...", state.trace_frame());
    return;
  }
  if (view.picked_point < 0) {
    ImGui::TextWrapped("Click a point in the 3D view to inspect it and its neighbourhood.");
    return;
  }
  const SceneDocument& doc = state.document();
  if (frame >= doc.scene.num_frames()) return;
  const render::SceneRenderData& data = *state.active_data();
  if (!data.trace()) {
    ImGui::TextWrapped("Building the model's hierarchy at frame %d...", frame);
    return;
  }
  const PointInfo info = inspect_point(data, view.picked_point, frame);
  // A forward pass carries the learned filter weights; a level view only the lists.
  const bool forward = trace && !is_level_view(*trace);
  ImGui::Text("point %d of the %s of level %d, frame %d (model point %d)", info.level_point,
              pick_set_name(PickSet::kLevel), view.level, frame, info.cloud_point);
  ImGui::SameLine();
  if (ImGui::SmallButton("clear")) {
    out.add([](ViewerState& s) { s.select_point(-1); });
    return;
  }
  ImGui::Text("object   %d %s", info.object_id, info.object_name.c_str());
  ImGui::Text("position %s", format_vec(info.position).c_str());
  if (info.has_velocity) {
    ImGui::Text("velocity %s  |v| %.3f", format_vec(info.velocity).c_str(), info.velocity.norm());
  }
  if (forward) draw_trace_features(*trace, view.level, view.picked_point);
  bool edges = view.layers.neighborhoods;
  if (ImGui::Checkbox("show edges", &edges)) {
    out.add([edges](ViewerState& s) { s.layers().neighborhoods = edges; });
  }
  if (!forward) {
    ImGui::SameLine();
    ImGui::TextColored(kMutedText, "(no checkpoint: lists only)");
  }
  const Neighborhood n = point_neighborhood(data, view.picked_point, frame);
  const bool weighted = state.trace_picked() == view.picked_point;
  const ImVec4 blue(0.35f, 0.6f, 1.0f, 1.0f), orange(1.0f, 0.6f, 0.15f, 1.0f);
  ImGui::TextColored(blue, "object kNN: %zu of k=%d (same object)", n.object.size(), n.k);
  if (!n.object_conv.empty()) ImGui::TextColored(kMutedText, "h of %s", n.object_conv.c_str());
  neighbour_table("knn", n.object, blue, forward);
  ImGui::TextColored(orange, "relational: %zu within r=%.3g (other objects)", n.relational.size(),
                     n.radius);
  if (!n.relational_conv.empty()) {
    ImGui::TextColored(kMutedText, "h of %s", n.relational_conv.c_str());
  }
  neighbour_table("rel", n.relational, orange, forward);
  if (forward && !weighted) ImGui::TextColored(kMutedText, "capturing filter weights...");
  if (trace && trace->source == kTraceSourceRollout && state.truth_input_levels()) {
    draw_input_difference(*trace, *state.truth_input_levels(), view.level, view.picked_point);
  }
  if (trace && trace->has_mesh) draw_trace_mesh(state, *trace, out);
}

}  // namespace dynscope::app::viewer
