// ViewerApp: setup, the frame loop (input, jobs, panels → actions, 3D view, UI) and cleanup.
#include "app/viewer/viewer_app.h"

#include <imgui.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "app/viewer/panel_util.h"
#include "engine/core/error.h"
#include "engine/core/threads.h"
#include "render/png_io.h"

namespace dynscope::app::viewer {
namespace {

constexpr float kClickSlop = 3.0f;  // pixels a press may move and still count as a click

}  // namespace

ViewerApp::ViewerApp(render::GlContext& context, Platform& platform, ModelServices* services)
    : context_(context),
      platform_(platform),
      state_(services),
      renderer_(context),
      imgui_(context) {
  sync_layout();
}

ViewerApp::~ViewerApp() = default;

void ViewerApp::sync_layout() {
  state_.set_layout({context_.width(), context_.height(), ui_visible_});
}

void ViewerApp::set_ui_visible(bool visible) {
  ui_visible_ = visible;
  sync_layout();
}

render::Image ViewerApp::read_pixels() {
  context_.make_current();
  return context_.read_pixels();
}

bool ViewerApp::pick(int x, int y) {
  state_.ensure_render_data();
  const std::vector<Viewport> ports = viewports();
  if (ports.empty()) return false;
  const Viewport& port = ports[static_cast<size_t>(viewport_at(ports, x))];
  const PickScene target = pick_scene(state_, port);
  if (target.scene.points.empty()) return false;
  const render::PickResult hit = renderer_.pick(target.scene, port.camera, x, y);
  if (!hit.hit()) return false;
  state_.select(target.sets[static_cast<size_t>(hit.layer)], hit.point);
  return true;
}

int64_t ViewerApp::upload_count() const {
  return renderer_.upload_count() + (view_thread_ ? view_thread_->upload_count() : 0);
}

void ViewerApp::set_view_thread(bool on) {
  if (on == view_thread()) return;
  if (on) {
    view_thread_ = std::make_unique<render::ViewThread>();
  } else {
    view_thread_.reset();
  }
  view_texture_ = nullptr;
}

void ViewerApp::wait_for_view() {
  if (view_thread_) view_thread_->wait(view_thread_->submitted());
}

int64_t ViewerApp::view_images() const { return view_thread_ ? view_thread_->images_drawn() : 0; }

void ViewerApp::hand_view_to_thread(const std::vector<Viewport>& ports, bool wait) {
  render::ViewRequest request;
  request.width = context_.width();
  request.height = context_.height();
  request.clear = state_.view().background;
  for (const Viewport& p : ports) request.items.push_back({p.scene, p.camera, p.rect});
  const uint64_t number = view_thread_->submit(std::move(request));
  if (wait) view_thread_->wait(number);
  render::Image image;
  uint64_t drawn = 0;
  try {
    if (view_thread_->take(image, drawn)) {
      const double start = thread_cpu_ms();
      view_texture_ = imgui_.show_image(image);
      view_upload_ms_ = thread_cpu_ms() - start;
    }
  } catch (const std::exception& e) {
    state_.select_point(-1);
    report(e);
  }
  // Behind everything ImGui draws, so captions and panels stay on top.
  if (view_texture_ != nullptr) {
    ImGui::GetBackgroundDrawList()->AddImage(
        view_texture_, ImVec2(0, 0),
        ImVec2(static_cast<float>(context_.width()), static_cast<float>(context_.height())));
  }
}

void ViewerApp::report(const std::exception& e) {
  error_ = e.what();
  error_pending_ = true;
  ++error_count_;
}

void ViewerApp::request_open(const std::string& path) {
  post([path](ViewerState& s) { s.open_file(path); });
}

void ViewerApp::handle_input() {
  const ImGuiIO& io = ImGui::GetIO();
  if (!io.WantCaptureMouse) {
    render::Camera& camera = state_.camera();
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
  const int frames = state_.num_frames();
  if (frames == 0 || io.WantTextInput) return;
  const int f = state_.current_frame();
  if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Space), false)) {
    state_.timeline().playing = !state_.timeline().playing;
  }
  if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_RightArrow))) state_.set_frame(f + 1);
  if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_LeftArrow))) state_.set_frame(f - 1);
  if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Home), false)) state_.set_frame(0);
  if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_End), false)) state_.set_frame(frames - 1);
}

void ViewerApp::apply(Actions& actions) {
  for (Action& a : actions.list) {
    try {
      a(state_);
    } catch (const std::exception& e) {
      report(e);
    }
  }
  if (!actions.screenshot.empty()) screenshot_path_ = actions.screenshot;
}

void ViewerApp::frame() {
  const double start = thread_cpu_ms();
  context_.make_current();
  sync_layout();
  platform_.new_frame();
  ImGui::NewFrame();
  if (!posted_.empty()) {
    Actions posted;
    posted.list = std::move(posted_);
    posted_.clear();
    apply(posted);
  }
  try {
    state_.update_jobs();
    handle_input();
    state_.advance_playback(ImGui::GetIO().DeltaTime);
    state_.ensure_render_data(/*in_background=*/true);
  } catch (const std::exception& e) {
    report(e);
  }
  Actions actions;
  if (ui_visible_) draw_panels(actions);
  apply(actions);
  std::vector<Viewport> ports;
  try {
    ports = viewports();
  } catch (const std::exception& e) {
    // A view that cannot be drawn (e.g. a stale picked point) falls back to no selection.
    state_.select_point(-1);
    report(e);
  }
  error_popup_open_ = false;
  view_upload_ms_ = 0.0;
  if (view_thread_) hand_view_to_thread(ports, !screenshot_path_.empty());
  if (ui_visible_) {
    draw_viewport_captions(ports);
    draw_error_popup();
  }
  ImGui::Render();
  const double gl_start = thread_cpu_ms();
  render_view(ports);
  if (ui_visible_ || view_thread_) imgui_.render(ImGui::GetDrawData());
  double gl = thread_cpu_ms() - gl_start + view_upload_ms_;
  if (!screenshot_path_.empty()) {
    try {
      render::write_png(screenshot_path_, context_.read_pixels());
    } catch (const std::exception& e) {
      report(e);
    }
    screenshot_path_.clear();
  }
  const double swap_start = thread_cpu_ms();
  context_.swap_buffers();
  const double end = thread_cpu_ms();
  gl += end - swap_start;
  frame_cpu_ = {end - start, gl};
}

void ViewerApp::render_view(const std::vector<Viewport>& ports) {
  if (view_thread_) {
    // The view thread's image covers the window; until the first one, the background.
    if (view_texture_ == nullptr) renderer_.clear(state_.view().background);
    return;
  }
  try {
    if (ports.empty()) renderer_.clear(state_.view().background);
    for (const Viewport& p : ports) renderer_.render(p.scene, p.camera, p.rect);
  } catch (const std::exception& e) {
    state_.select_point(-1);
    report(e);
  }
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

void ViewerApp::draw_panels(Actions& actions) {
  for (const auto& [panel, open] : state_.take_open_requests()) open_requests_[panel] = open;
  if (fields_.synced_generation != state_.generation()) {
    // A new document or checkpoint: the text fields show what is open now.
    fields_.synced_generation = state_.generation();
    const RolloutDocument* r = state_.rollout_document();
    if (r && std::filesystem::is_regular_file(r->path)) {
      fields_.open_path = r->path;
    } else if (const SceneDocument* d = state_.scene_document()) {
      fields_.open_path = d->path;
    }
    fields_.checkpoint = state_.checkpoint();
  }
  const ImGuiIO& io = ImGui::GetIO();
  const ImGuiWindowFlags fixed =
      ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse;
  ImGui::SetNextWindowPos(ImVec2(0, 0), ImGuiCond_Always);
  const SceneDocument* doc = state_.scene_document();
  const RolloutDocument* rollout = state_.rollout_document();
  const std::string shown = rollout ? rollout->path : doc ? doc->path : "";
  const std::string title =
      (shown.empty() ? std::string("dynscope") : "dynscope - " + file_name(shown)) + "###panel";
  const float bottom = timeline_height(state_.layout(), rollout != nullptr);
  ImGui::SetNextWindowSize(ImVec2(panel_width(state_.layout()), io.DisplaySize.y - bottom),
                           ImGuiCond_Always);
  if (ImGui::Begin(title.c_str(), nullptr, fixed)) {
    try {
      if (section("Files", Panel::kFiles, !doc && !rollout)) {
        draw_files_panel(state_, fields_, actions);
      }
      if (section("Display", Panel::kDisplay, false)) draw_display_panel(state_, actions);
      if (rollout && section("Rollout", Panel::kRollout, true)) {
        draw_rollout_panel(state_, actions);
      }
      if (state_.has_services() && section("Model", Panel::kModel, !state_.checkpoint().empty())) {
        draw_model_panel(state_, fields_, actions);
      }
      if (rollout && state_.has_services() && section("Explain", Panel::kExplain, false)) {
        draw_explain_panel(state_, fields_, actions);
      }
      if (doc) {
        if (section("Objects", Panel::kObjects, true)) {
          draw_objects_panel(state_, fields_, actions);
        }
        if (section("Contact timeline", Panel::kContacts, false)) {
          draw_contacts_panel(state_, actions);
        }
        if (section("U-Net levels", Panel::kLevels, false)) draw_levels_panel(state_, actions);
        if (section("Selection & neighbourhood", Panel::kInspector, false)) {
          draw_inspector_panel(state_, actions);
        }
      } else if (!rollout) {
        ImGui::TextWrapped(
            "No scene loaded: enter a scene, rollout or trace file (.h5) under Files and press "
            "Open.");
      }
    } catch (const std::exception& e) {
      report(e);
    }
  }
  ImGui::End();
  draw_timeline_panel(state_, actions);
}

void ViewerApp::draw_viewport_captions(const std::vector<Viewport>& viewports) {
  ImDrawList* draw = ImGui::GetBackgroundDrawList();
  const float left = panel_width(state_.layout());
  const float bottom = timeline_height(state_.layout(), state_.has_rollout());
  for (size_t i = 0; i < viewports.size(); ++i) {
    const Viewport& p = viewports[i];
    const float x0 = static_cast<float>(p.rect.x);
    const float x1 = static_cast<float>(p.rect.x + p.rect.width);
    if (i > 0) {
      draw->AddLine(ImVec2(x0, 0.0f), ImVec2(x0, static_cast<float>(context_.height()) - bottom),
                    IM_COL32(90, 90, 90, 255), 2.0f);
    }
    if (p.caption.empty()) continue;
    const std::string text = file_name(p.caption);
    const ImVec2 size = ImGui::CalcTextSize(text.c_str());
    const float x = 0.5f * (std::max(x0, left) + x1 - size.x);
    draw->AddRectFilled(ImVec2(x - 4, 6), ImVec2(x + size.x + 4, 10 + size.y),
                        IM_COL32(255, 255, 255, 200));
    draw->AddText(ImVec2(x, 8), IM_COL32(20, 20, 20, 255), text.c_str());
  }
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
  error_popup_open_ = ImGui::BeginPopupModal("Error", nullptr, ImGuiWindowFlags_NoMove);
  if (error_popup_open_) {
    ImGui::TextWrapped("%s", error_.c_str());
    if (ImGui::Button("OK", ImVec2(80, 0))) ImGui::CloseCurrentPopup();
    ImGui::EndPopup();
  }
}

}  // namespace dynscope::app::viewer
