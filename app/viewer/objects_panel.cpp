// Objects panel: the scene's object table and the what-if editor of one object's initial state.
#include "app/viewer/panel_util.h"
#include "app/viewer/panels.h"

namespace dynscope::app::viewer {
namespace {

void draw_what_if(const ViewerState& state, PanelFields& fields, Actions& out) {
  const Scene& scene = state.document().scene;
  const int edit_frame = state.observed_frames() - 1;
  if (fields.edit_generation != state.generation()) {
    // Another scene or checkpoint: the fields filled from the old one mean nothing here.
    fields.edit_object = -1;
    fields.edit_generation = state.generation();
  }
  ImGui::Separator();
  ImGui::TextUnformatted("What-if");
  ImGui::TextColored(kMutedText, "initial state at frame %d (last observed)", edit_frame);
  const std::string current = fields.edit_object >= 0
                                  ? scene.objects[static_cast<size_t>(fields.edit_object)].name
                                  : "(object)";
  ImGui::SetNextItemWidth(160);
  if (ImGui::BeginCombo("object", current.c_str())) {
    for (size_t i = 0; i < scene.objects.size(); ++i) {
      const bool selected = fields.edit_object == static_cast<int>(i);
      if (ImGui::Selectable(scene.objects[i].name.c_str(), selected)) {
        fields.edit_object = static_cast<int>(i);
        fields.edit = object_initial_state(scene, fields.edit_object, edit_frame);
      }
    }
    ImGui::EndCombo();
  }
  if (fields.edit_object < 0) return;
  ImGui::SameLine();
  if (ImGui::SmallButton("reset")) {
    fields.edit = object_initial_state(scene, fields.edit_object, edit_frame);
  }
  ObjectEdit& edit = fields.edit;
  ImGui::InputScalarN("position", ImGuiDataType_Double, edit.position.data(), 3, nullptr, nullptr,
                      "%.3f");
  ImGui::InputScalarN("euler deg", ImGuiDataType_Double, edit.euler_deg.data(), 3, nullptr, nullptr,
                      "%.1f");
  ImGui::InputScalarN("velocity", ImGuiDataType_Double, edit.velocity.data(), 3, nullptr, nullptr,
                      "%.3f");
  const auto* job = state.rollout_job();
  ImGui::BeginDisabled(job != nullptr);
  if (ImGui::Button("Re-run rollout")) {
    out.add([edit](ViewerState& s) { s.start_what_if(edit); });
  }
  ImGui::EndDisabled();
  if (job) {
    ImGui::SameLine();
    ImGui::ProgressBar(job->fraction(), ImVec2(-1, 0));
  }
  ImGui::TextColored(kMutedText, "earlier frames move rigidly with the edit");
}

}  // namespace

void draw_objects_panel(const ViewerState& state, PanelFields& fields, Actions& out) {
  const SceneDocument& doc = state.document();
  const Scene& scene = doc.scene;
  const ScenePointCloud& cloud = doc.data->cloud();
  const ImGuiTableFlags flags =
      ImGuiTableFlags_Borders | ImGuiTableFlags_RowBg | ImGuiTableFlags_SizingFixedFit;
  ImGui::Text("%s, %zu objects, %d frames, dt %.4g s", scene.scenario.c_str(), scene.objects.size(),
              scene.num_frames(), scene.dt_s);
  if (!ImGui::BeginTable("objects", 7, flags)) return;
  for (const char* h : {"id", "name", "role", "mass", "fric", "rest", "pts"}) {
    ImGui::TableSetupColumn(h);
  }
  ImGui::TableHeadersRow();
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const Object& o = scene.objects[i];
    ImGui::TableNextRow();
    ImGui::TableNextColumn();
    ImGui::ColorButton("##c", to_imvec(render::categorical_color(o.id)),
                       ImGuiColorEditFlags_NoTooltip, ImVec2(10, 10));
    ImGui::SameLine();
    ImGui::Text("%d", o.id);
    ImGui::TableNextColumn();
    ImGui::TextUnformatted(o.name.c_str());
    ImGui::TableNextColumn();
    ImGui::TextUnformatted(role_name(o.role));
    ImGui::TableNextColumn();
    ImGui::Text(o.is_static() ? "static" : "%.3g", o.mass);
    ImGui::TableNextColumn();
    ImGui::Text("%.2f", o.friction);
    ImGui::TableNextColumn();
    ImGui::Text("%.2f", o.restitution);
    ImGui::TableNextColumn();
    ImGui::Text("%lld", static_cast<long long>(cloud.count_of(static_cast<int>(i))));
  }
  ImGui::EndTable();
  if (state.has_services() && !state.checkpoint().empty()) draw_what_if(state, fields, out);
}

}  // namespace dynscope::app::viewer
