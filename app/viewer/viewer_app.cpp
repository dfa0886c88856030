// ViewerApp: panels (ImGui), 3D view (Renderer), picking, timeline and file actions.
#include "app/viewer/viewer_app.h"

#include <imgui.h>
#include <imgui_stdlib.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "engine/core/error.h"
#include "engine/io/scene_file.h"
#include "render/png_io.h"

namespace dynscope::app::viewer {
namespace {

constexpr float kPanelWidth = 370.0f;
constexpr float kTimelineHeight = 58.0f;
constexpr int kMaxLevel = 3;        // the U-Net's 4 levels (DESIGN §5)
constexpr float kClickSlop = 3.0f;  // pixels a press may move and still count as a click
const ImVec4 kMutedText(0.65f, 0.65f, 0.65f, 1.0f);

ImVec4 to_imvec(const render::Color& c) { return ImVec4(c.x(), c.y(), c.z(), 1.0f); }

std::string format_vec(const Vec3& v, const char* format = "%.3f") {
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

}  // namespace

ViewerApp::ViewerApp(render::GlContext& context, Platform& platform)
    : context_(context), platform_(platform), renderer_(context), imgui_(context) {
  view_.layers.level_points = true;
}

ViewerApp::~ViewerApp() = default;

const SceneDocument& ViewerApp::document() const {
  if (!doc_) throw ValueError("scene", "no scene is loaded");
  return *doc_;
}

void ViewerApp::open_scene(const std::string& path) { set_scene(read_scene(path), path); }

void ViewerApp::set_scene(const Scene& scene, const std::string& path) {
  scene.validate();
  auto doc = std::make_unique<SceneDocument>();
  doc->path = path;
  doc->scene = scene;
  render::ViewSpec build = view_;
  build.layers.level_points = true;
  build.picked_point = -1;
  build.frame = 0;
  doc->data = std::make_unique<render::SceneRenderData>(doc->scene, build);
  doc->contact_distance = contact_distances(doc->scene, doc->data->cloud());
  doc_ = std::move(doc);
  data_level_ = view_.level;
  scene_field_ = path;
  view_.frame = 0;
  view_.picked_point = -1;
  timeline_ = Timeline{};
  view_.camera.fit = true;
  fit_camera();
}

void ViewerApp::set_view(const render::ViewSpec& view) {
  view.validate();
  if (doc_ && view.frame >= doc_->scene.num_frames()) {
    throw ValueError("frame", std::to_string(view.frame) + " is outside the scene's " +
                                  std::to_string(doc_->scene.num_frames()) + " frames");
  }
  const render::ViewSpec previous = view_;
  view_ = view;
  // Voxel, radius or point size may differ: rebuild the level data from scratch.
  data_level_ = -1;
  try {
    ensure_render_data();
    if (doc_ && view_.picked_point >= static_cast<int>(doc_->data->level_indices().size())) {
      throw ValueError("picked_point",
                       std::to_string(view_.picked_point) + " is outside the level's points");
    }
  } catch (...) {
    view_ = previous;
    data_level_ = -1;
    ensure_render_data();
    throw;
  }
  if (view_.camera.fit) fit_camera();
  if (view_.picked_point >= 0) show_panel(Panel::kInspector);
  if (view_.level > 0 || view_.layers.voxels) show_panel(Panel::kLevels);
}

void ViewerApp::open_view(const std::string& path) {
  set_view(render::load_view_spec(path));
  view_field_ = path;
}

render::ViewSpec ViewerApp::current_view() const {
  render::ViewSpec v = view_;
  v.width = context_.width();
  v.height = context_.height();
  v.camera.fit = false;
  v.camera.preset.clear();
  return v;
}

void ViewerApp::save_view(const std::string& path) const {
  render::save_view_spec(current_view(), path);
}

void ViewerApp::set_frame(int frame) {
  if (!doc_) return;
  view_.frame = std::clamp(frame, 0, doc_->scene.num_frames() - 1);
}

void ViewerApp::select_point(int point) {
  if (point >= 0) {
    ensure_render_data();
    const int n = doc_ ? static_cast<int>(doc_->data->level_indices().size()) : 0;
    if (point >= n) {
      throw ValueError("picked_point", std::to_string(point) + " is outside the " +
                                           std::to_string(n) + " points of level " +
                                           std::to_string(view_.level));
    }
    view_.layers.neighborhoods = true;
    show_panel(Panel::kInspector);
  }
  view_.picked_point = std::max(point, -1);
}

void ViewerApp::set_level(int level) {
  if (level < 0 || level > kMaxLevel) {
    throw ValueError("level",
                     std::to_string(level) + " is outside 0.." + std::to_string(kMaxLevel));
  }
  if (level == view_.level) return;
  view_.level = level;
  view_.picked_point = -1;  // indices of another level's points mean nothing here
  ensure_render_data();
}

void ViewerApp::show_panel(Panel panel) { open_requests_[panel] = true; }

void ViewerApp::ensure_render_data() {
  if (!doc_ || (doc_->data && data_level_ == view_.level)) return;
  render::ViewSpec build = view_;
  build.layers.level_points = true;  // points are always prepared so they can be picked
  build.picked_point = -1;
  build.frame = 0;
  doc_->data = std::make_unique<render::SceneRenderData>(doc_->scene, build);
  data_level_ = view_.level;
}

void ViewerApp::fit_camera() {
  if (!doc_) return;
  render::Camera& camera = view_.camera.camera;
  if (!view_.camera.preset.empty()) camera.set_preset(render::parse_preset(view_.camera.preset));
  const double w = context_.width(), h = context_.height();
  // Fit into the part of the window the panels leave free, then shift the view so the scene is
  // centred there (the 3D view itself spans the whole window, behind the panels).
  const double left = ui_visible_ ? kPanelWidth : 0.0;
  const double bottom = ui_visible_ ? kTimelineHeight : 0.0;
  const double vw = std::max(1.0, w - left), vh = std::max(1.0, h - bottom);
  const Aabb bounds = doc_->data->bounds(0, doc_->scene.num_frames() - 1);
  camera.fit(bounds, vw / vh);
  if (!bounds.empty()) {
    const double radius = std::max(0.5 * (bounds.max - bounds.min).norm(), 1e-3);
    const double tan_half = std::tan(camera.fov_deg * M_PI / 360.0);
    const double half = std::min(std::atan(tan_half * vh / h), std::atan(tan_half * vw / h));
    camera.distance = 1.1 * radius / std::sin(half);
    camera.pan(-0.5 * left / h, -0.5 * bottom / h);
  }
  view_.camera.fit = false;
  view_.camera.preset.clear();
}

render::RenderScene ViewerApp::pick_scene() const {
  // Only the level's points, so a hit's index is a level point index.
  render::ViewSpec v = view_;
  v.layers = render::ViewLayers{};
  v.layers.grid = false;
  v.layers.meshes = false;
  v.layers.prediction = false;
  v.layers.level_points = true;
  v.picked_point = -1;
  return doc_->data->frame(view_.frame, v);
}

bool ViewerApp::pick(int x, int y) {
  if (!doc_) return false;
  ensure_render_data();
  const render::PickResult hit = renderer_.pick(pick_scene(), view_.camera.camera, x, y);
  if (!hit.hit()) return false;
  select_point(hit.point);
  return true;
}

void ViewerApp::report(const std::exception& e) {
  error_ = e.what();
  error_pending_ = true;
}

void ViewerApp::handle_input() {
  const ImGuiIO& io = ImGui::GetIO();
  if (!io.WantCaptureMouse) {
    render::Camera& camera = view_.camera.camera;
    const float h = std::max(1.0f, io.DisplaySize.y);
    if (ImGui::IsMouseClicked(ImGuiMouseButton_Left)) {
      dragging_ = true;
      drag_distance_ = 0.0f;
    }
    if (dragging_) drag_distance_ += std::fabs(io.MouseDelta.x) + std::fabs(io.MouseDelta.y);
    if (ImGui::IsMouseDown(ImGuiMouseButton_Left) && drag_distance_ > kClickSlop) {
      camera.orbit(-0.3 * io.MouseDelta.x, 0.3 * io.MouseDelta.y);
    }
    if (ImGui::IsMouseDown(ImGuiMouseButton_Right) || ImGui::IsMouseDown(ImGuiMouseButton_Middle)) {
      camera.pan(-io.MouseDelta.x / h, io.MouseDelta.y / h);
    }
    if (io.MouseWheel != 0.0f) camera.zoom(std::pow(0.9, io.MouseWheel));
    if (ImGui::IsMouseReleased(ImGuiMouseButton_Left) && dragging_) {
      dragging_ = false;
      if (drag_distance_ <= kClickSlop) {
        pick(static_cast<int>(io.MousePos.x), static_cast<int>(io.MousePos.y));
      }
    }
  } else if (!ImGui::IsMouseDown(ImGuiMouseButton_Left)) {
    dragging_ = false;
  }
  if (!doc_ || io.WantTextInput) return;
  if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Space), false)) {
    timeline_.playing = !timeline_.playing;
  }
  if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_RightArrow))) set_frame(view_.frame + 1);
  if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_LeftArrow))) set_frame(view_.frame - 1);
  if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Home), false)) set_frame(0);
  if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_End), false)) {
    set_frame(doc_->scene.num_frames() - 1);
  }
}

void ViewerApp::advance_playback(float dt_s) {
  if (!doc_ || !timeline_.playing) return;
  const int last = doc_->scene.num_frames() - 1;
  timeline_.accumulated_s += dt_s * timeline_.speed;
  while (timeline_.accumulated_s >= doc_->scene.dt_s) {
    timeline_.accumulated_s -= doc_->scene.dt_s;
    if (view_.frame < last) {
      ++view_.frame;
    } else if (timeline_.loop) {
      view_.frame = 0;
    } else {
      timeline_.playing = false;
      timeline_.accumulated_s = 0.0;
      break;
    }
  }
}

void ViewerApp::frame() {
  context_.make_current();
  platform_.new_frame();
  ImGui::NewFrame();
  try {
    handle_input();
    advance_playback(ImGui::GetIO().DeltaTime);
    ensure_render_data();
  } catch (const std::exception& e) {
    report(e);
  }
  if (ui_visible_) draw_panels();
  ImGui::Render();

  try {
    if (doc_) {
      renderer_.render(doc_->data->frame(view_.frame, view_), view_.camera.camera);
    } else {
      const render::GlFunctions& gl = renderer_.gl();
      gl.BindFramebuffer(GL_FRAMEBUFFER, 0);
      gl.Viewport(0, 0, context_.width(), context_.height());
      gl.ClearColor(view_.background.x(), view_.background.y(), view_.background.z(), 1.0f);
      gl.Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    }
  } catch (const std::exception& e) {
    // A view that cannot be drawn (e.g. a stale picked point) falls back to no selection.
    view_.picked_point = -1;
    report(e);
  }
  if (ui_visible_) imgui_.render(ImGui::GetDrawData());
  if (!screenshot_path_.empty()) {
    try {
      render::write_png(screenshot_path_, context_.read_pixels());
    } catch (const std::exception& e) {
      report(e);
    }
    screenshot_path_.clear();
  }
  context_.swap_buffers();
}

render::Image ViewerApp::read_pixels() {
  context_.make_current();
  return context_.read_pixels();
}

bool ViewerApp::section(const char* label, Panel panel, bool default_open) {
  auto request = open_requests_.find(panel);
  if (request != open_requests_.end()) {
    ImGui::SetNextItemOpen(request->second, ImGuiCond_Always);
    open_requests_.erase(request);
  } else {
    ImGui::SetNextItemOpen(default_open, ImGuiCond_Once);
  }
  return ImGui::CollapsingHeader(label);
}

void ViewerApp::draw_panels() {
  const ImGuiIO& io = ImGui::GetIO();
  const ImGuiWindowFlags fixed =
      ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse;
  ImGui::SetNextWindowPos(ImVec2(0, 0), ImGuiCond_Always);
  ImGui::SetNextWindowSize(ImVec2(kPanelWidth, io.DisplaySize.y - kTimelineHeight),
                           ImGuiCond_Always);
  const std::string title =
      (doc_ ? "dynscope - " + file_name(doc_->path) : std::string("dynscope")) + "###panel";
  if (ImGui::Begin(title.c_str(), nullptr, fixed)) {
    try {
      if (section("Files", Panel::kFiles, !doc_)) draw_files_section();
      if (section("Display", Panel::kDisplay, false)) draw_display_section();
      if (doc_) {
        if (section("Objects", Panel::kObjects, true)) draw_objects_section();
        if (section("Contact timeline", Panel::kContacts, false)) draw_contacts_section();
        if (section("U-Net levels", Panel::kLevels, false)) draw_levels_section();
        if (section("Selection & neighbourhood", Panel::kInspector, false)) {
          draw_inspector_section();
        }
      } else {
        ImGui::TextWrapped("No scene loaded: enter a scene file (.h5) under Files and press Open.");
      }
    } catch (const std::exception& e) {
      report(e);
    }
  }
  ImGui::End();
  draw_timeline();
  draw_error_popup();
}

void ViewerApp::draw_files_section() {
  ImGui::PushItemWidth(-90.0f);
  ImGui::InputText("##scene", &scene_field_);
  ImGui::SameLine();
  if (ImGui::Button("Open scene", ImVec2(-1, 0))) {
    try {
      open_scene(scene_field_);
    } catch (const std::exception& e) {
      report(e);
    }
  }
  ImGui::InputText("##view", &view_field_);
  ImGui::SameLine();
  if (ImGui::Button("Save view", ImVec2(-1, 0))) {
    try {
      save_view(view_field_);
    } catch (const std::exception& e) {
      report(e);
    }
  }
  ImGui::Dummy(ImVec2(0, 0));
  ImGui::SameLine(ImGui::GetContentRegionAvail().x - 82.0f);
  if (ImGui::Button("Open view", ImVec2(-1, 0))) {
    try {
      open_view(view_field_);
    } catch (const std::exception& e) {
      report(e);
    }
  }
  ImGui::InputText("##png", &screenshot_field_);
  ImGui::SameLine();
  if (ImGui::Button("Screenshot", ImVec2(-1, 0))) request_screenshot(screenshot_field_);
  ImGui::PopItemWidth();
}

void ViewerApp::draw_display_section() {
  render::ViewLayers& l = view_.layers;
  ImGui::Checkbox("meshes", &l.meshes);
  ImGui::SameLine(120);
  ImGui::Checkbox("grid", &l.grid);
  ImGui::SameLine(220);
  ImGui::Checkbox("all points", &l.ground_truth);
  ImGui::Checkbox("level points", &l.level_points);
  ImGui::SameLine(120);
  ImGui::Checkbox("voxels", &l.voxels);
  ImGui::SameLine(220);
  ImGui::Checkbox("neighbours", &l.neighborhoods);
  ImGui::Checkbox("interaction points", &l.interaction_points);
  ImGui::TextUnformatted("camera");
  for (render::ViewPreset p : {render::ViewPreset::kFront, render::ViewPreset::kSide,
                               render::ViewPreset::kTop, render::ViewPreset::kIso}) {
    ImGui::SameLine();
    if (ImGui::SmallButton(render::preset_name(p))) {
      view_.camera.preset = render::preset_name(p);
      fit_camera();
    }
  }
  ImGui::SameLine();
  if (ImGui::SmallButton("fit")) fit_camera();
  ImGui::TextColored(kMutedText, "drag: orbit, right drag: pan, wheel: zoom, click: pick");
}

void ViewerApp::draw_objects_section() {
  const Scene& scene = doc_->scene;
  const ScenePointCloud& cloud = doc_->data->cloud();
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
    ImGui::Text(o.mass == 0.0 ? "static" : "%.3g", o.mass);
    ImGui::TableNextColumn();
    ImGui::Text("%.2f", o.friction);
    ImGui::TableNextColumn();
    ImGui::Text("%.2f", o.restitution);
    ImGui::TableNextColumn();
    ImGui::Text("%lld", static_cast<long long>(cloud.count_of(static_cast<int>(i))));
  }
  ImGui::EndTable();
}

void ViewerApp::draw_contacts_section() {
  const Scene& scene = doc_->scene;
  const std::vector<double>& d = doc_->contact_distance;
  if (d.empty()) {
    ImGui::TextWrapped("This scene has no target and zone object (no contact timeline).");
  } else {
    std::vector<float> values(d.begin(), d.end());
    const float top = std::max(1e-3f, *std::max_element(values.begin(), values.end()));
    char overlay[64];
    std::snprintf(overlay, sizeof(overlay), "frame %d: %.3f", view_.frame, d[view_.frame]);
    ImGui::PlotLines("##dist", values.data(), static_cast<int>(values.size()), 0, overlay, 0.0f,
                     top, ImVec2(-1, 60));
    ImGui::TextColored(kMutedText, "target-zone minimum point distance over time");
  }
  for (const auto& [name, values] : scene.labels) {
    const auto first = std::find_if(values.begin(), values.end(), [](double v) { return v > 0.5; });
    ImGui::Text(
        "%s: %s", name.c_str(),
        view_.frame < static_cast<int>(values.size()) && values[view_.frame] > 0.5 ? "yes" : "no");
    ImGui::SameLine();
    if (first == values.end()) {
      ImGui::TextColored(kMutedText, "(never)");
    } else {
      ImGui::TextColored(kMutedText, "(first at frame %d)",
                         static_cast<int>(first - values.begin()));
    }
  }
}

void ViewerApp::draw_levels_section() {
  const render::SceneRenderData& data = *doc_->data;
  int level = view_.level;
  ImGui::SetNextItemWidth(150);
  if (ImGui::SliderInt("level", &level, 0, kMaxLevel)) set_level(level);
  ImGui::SameLine();
  ImGui::Checkbox("points", &view_.layers.level_points);
  ImGui::SameLine();
  ImGui::Checkbox("voxels", &view_.layers.voxels);
  ImGui::Text("shown: %zu points, voxel %.3g, radius %.3g", doc_->data->level_indices().size(),
              data.level_voxel(), data.level_radius());
  auto cached = doc_->level_counts.find(view_.frame);
  if (cached == doc_->level_counts.end()) {
    cached = doc_->level_counts
                 .emplace(view_.frame, level_counts(doc_->scene, data.cloud(), view_.frame))
                 .first;
  }
  const std::vector<LevelCount>& counts = cached->second;
  ImGui::TextColored(kMutedText, "model hierarchy (%s preset) at frame %d",
                     hierarchy_preset(doc_->scene).c_str(), view_.frame);
  const Scene& scene = doc_->scene;
  const int columns = 3 + static_cast<int>(scene.objects.size());
  const ImGuiTableFlags flags =
      ImGuiTableFlags_Borders | ImGuiTableFlags_RowBg | ImGuiTableFlags_SizingFixedFit;
  if (!ImGui::BeginTable("levels", columns, flags)) return;
  ImGui::TableSetupColumn("lvl");
  ImGui::TableSetupColumn("voxel");
  ImGui::TableSetupColumn("points");
  for (const Object& o : scene.objects)
    ImGui::TableSetupColumn(("obj " + std::to_string(o.id)).c_str());
  ImGui::TableHeadersRow();
  for (const LevelCount& c : counts) {
    ImGui::TableNextRow();
    if (c.level == view_.level) {
      ImGui::TableSetBgColor(ImGuiTableBgTarget_RowBg1, IM_COL32(60, 90, 140, 160));
    }
    ImGui::TableNextColumn();
    ImGui::Text("%d", c.level);
    ImGui::TableNextColumn();
    if (c.level == 0) {
      ImGui::TextUnformatted("-");
    } else {
      ImGui::Text("%.3g", c.voxel);
    }
    ImGui::TableNextColumn();
    ImGui::Text("%d", c.points);
    for (const Object& o : scene.objects) {
      ImGui::TableNextColumn();
      const auto it = c.per_object.find(o.id);
      ImGui::Text("%d", it == c.per_object.end() ? 0 : it->second);
    }
  }
  ImGui::EndTable();
}

void ViewerApp::draw_inspector_section() {
  if (view_.picked_point < 0) {
    ImGui::TextWrapped("Click a point in the 3D view to inspect it and its neighbourhood.");
    return;
  }
  const render::SceneRenderData& data = *doc_->data;
  const PointInfo info = inspect_point(data, view_.picked_point, view_.frame);
  ImGui::Text("point %d of level %d (cloud point %d)", info.level_point, view_.level,
              info.cloud_point);
  ImGui::SameLine();
  if (ImGui::SmallButton("clear")) {
    view_.picked_point = -1;
    return;
  }
  ImGui::Text("object   %d %s", info.object_id, info.object_name.c_str());
  ImGui::Text("position %s", format_vec(info.position).c_str());
  ImGui::Text("velocity %s  |v| %.3f", format_vec(info.velocity).c_str(), info.velocity.norm());
  ImGui::Checkbox("show edges", &view_.layers.neighborhoods);
  ImGui::SameLine();
  ImGui::SetNextItemWidth(110);
  ImGui::SliderInt("k", &view_.neighbors, 1, 32);
  const Neighborhood n = point_neighborhood(data, view_.picked_point, view_.frame, view_.neighbors);
  auto table = [](const char* id, const std::vector<NeighborEntry>& list, const ImVec4& color) {
    const ImGuiTableFlags flags = ImGuiTableFlags_Borders | ImGuiTableFlags_RowBg |
                                  ImGuiTableFlags_ScrollY | ImGuiTableFlags_SizingStretchSame;
    const float rows = static_cast<float>(std::min<size_t>(list.size(), 5) + 1);
    if (list.empty() || !ImGui::BeginTable(id, 3, flags, ImVec2(0, rows * 19.0f + 4.0f))) return;
    ImGui::TableSetupScrollFreeze(0, 1);
    ImGui::TableSetupColumn("point");
    ImGui::TableSetupColumn("object");
    ImGui::TableSetupColumn("distance");
    ImGui::TableHeadersRow();
    for (const NeighborEntry& e : list) {
      ImGui::TableNextRow();
      ImGui::TableNextColumn();
      ImGui::TextColored(color, "%d", e.point);
      ImGui::TableNextColumn();
      ImGui::Text("%d", e.object_id);
      ImGui::TableNextColumn();
      ImGui::Text("%.4f", e.distance);
    }
    ImGui::EndTable();
  };
  const ImVec4 blue(0.35f, 0.6f, 1.0f, 1.0f), orange(1.0f, 0.6f, 0.15f, 1.0f);
  ImGui::TextColored(blue, "object kNN: %zu of k=%d (same object)", n.object.size(), n.k);
  table("knn", n.object, blue);
  ImGui::TextColored(orange, "relational: %zu within r=%.3g (other objects)", n.relational.size(),
                     n.radius);
  table("rel", n.relational, orange);
}

void ViewerApp::draw_timeline() {
  const ImGuiIO& io = ImGui::GetIO();
  ImGui::SetNextWindowPos(ImVec2(0, io.DisplaySize.y - kTimelineHeight), ImGuiCond_Always);
  ImGui::SetNextWindowSize(ImVec2(io.DisplaySize.x, kTimelineHeight), ImGuiCond_Always);
  const ImGuiWindowFlags flags = ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize |
                                 ImGuiWindowFlags_NoCollapse | ImGuiWindowFlags_NoTitleBar |
                                 ImGuiWindowFlags_NoScrollbar;
  if (ImGui::Begin("Timeline", nullptr, flags)) {
    if (!doc_) {
      ImGui::TextColored(kMutedText, "timeline: no scene");
    } else {
      const int last = doc_->scene.num_frames() - 1;
      if (ImGui::Button("|<")) set_frame(0);
      ImGui::SameLine();
      if (ImGui::Button("<")) set_frame(view_.frame - 1);
      ImGui::SameLine();
      if (ImGui::Button(timeline_.playing ? "pause" : "play", ImVec2(48, 0))) {
        timeline_.playing = !timeline_.playing;
      }
      ImGui::SameLine();
      if (ImGui::Button(">")) set_frame(view_.frame + 1);
      ImGui::SameLine();
      if (ImGui::Button(">|")) set_frame(last);
      ImGui::SameLine();
      int frame = view_.frame;
      ImGui::SetNextItemWidth(std::max(100.0f, ImGui::GetContentRegionAvail().x - 330.0f));
      if (ImGui::SliderInt("##frame", &frame, 0, last, "frame %d")) set_frame(frame);
      ImGui::SameLine();
      ImGui::Text("t %.3f s", view_.frame * doc_->scene.dt_s);
      ImGui::SameLine();
      ImGui::SetNextItemWidth(90);
      ImGui::SliderFloat("speed", &timeline_.speed, 0.1f, 4.0f, "%.1fx");
      ImGui::SameLine();
      ImGui::Checkbox("loop", &timeline_.loop);
    }
    ImGui::TextColored(kMutedText, "space: play/pause   left/right: step   home/end: first/last");
  }
  ImGui::End();
}

void ViewerApp::draw_error_popup() {
  if (error_pending_) {
    ImGui::OpenPopup("Error");
    error_pending_ = false;
  }
  const ImGuiIO& io = ImGui::GetIO();
  ImGui::SetNextWindowPos(ImVec2(io.DisplaySize.x * 0.5f, io.DisplaySize.y * 0.5f),
                          ImGuiCond_Always, ImVec2(0.5f, 0.5f));
  ImGui::SetNextWindowSize(ImVec2(std::min(520.0f, io.DisplaySize.x - 20.0f), 0));
  if (ImGui::BeginPopupModal("Error", nullptr, ImGuiWindowFlags_NoMove)) {
    ImGui::TextWrapped("%s", error_.c_str());
    if (ImGui::Button("OK", ImVec2(80, 0))) ImGui::CloseCurrentPopup();
    ImGui::EndPopup();
  }
}

}  // namespace dynscope::app::viewer
