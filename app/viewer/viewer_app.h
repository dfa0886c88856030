// ViewerApp: the interactive viewer as a thin composition: setup (state, renderers), one frame
// of input, panels, 3D view and UI at a time, cleanup.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "app/viewer/imgui_renderer.h"
#include "app/viewer/model_services.h"
#include "app/viewer/panels.h"
#include "app/viewer/platform.h"
#include "app/viewer/viewer_state.h"
#include "app/viewer/viewports.h"
#include "render/gl_context.h"
#include "render/image.h"
#include "render/renderer.h"
#include "render/view_thread.h"

namespace dynscope::app::viewer {

/// CPU time of the UI thread in the last frame(), in milliseconds: all of it, and the part spent
/// inside GL calls (drawing, UI submission, read-back, swap). With a software driver (llvmpipe)
/// the vertex stage runs inside those calls on this thread; with a GPU driver it does not.
struct FrameCpu {
  double total_ms = 0.0;
  double gl_ms = 0.0;
  double app_ms() const { return total_ms - gl_ms; }  ///< State, panels, ImGui, viewports.
};

/// The viewer: a ViewerState, the panels that draw it and return actions, the Renderer for the
/// 3D view and the ImGuiRenderer for the panels. The 3D view fills the framebuffer behind the
/// panels, so picking and Camera::project use full-window pixels. Errors from user actions are
/// shown in a popup and never escape frame().
class ViewerApp {
 public:
  /// Draws into `context` (made current) with input from `platform`; an ImGuiSession must exist.
  /// `services` (may be null; must outlive the app) runs the model for rollouts and traces.
  /// Throws Error if GL setup fails.
  ViewerApp(render::GlContext& context, Platform& platform, ModelServices* services = nullptr);
  ~ViewerApp();
  ViewerApp(const ViewerApp&) = delete;
  ViewerApp& operator=(const ViewerApp&) = delete;

  /// The state the panels show (documents, view, jobs).
  ViewerState& state() { return state_; }
  const ViewerState& state() const { return state_; }

  /// Runs one frame: platform input, jobs, panels and their actions, 3D view, UI, screenshot,
  /// swap.
  void frame();
  /// Reads the framebuffer of the last frame (RGBA, rows top to bottom).
  render::Image read_pixels();
  /// The viewports the 3D view draws for the current state (one, or two side by side).
  std::vector<Viewport> viewports() const { return build_viewports(state_); }
  /// Picks the point drawn at pixel (x, y) (origin top-left) as a click would; returns whether a
  /// point was hit.
  bool pick(int x, int y);
  /// Runs `action` on the state during the next frame, before the panels, as a panel's button
  /// would: a failure becomes the error popup.
  void post(Action action) { posted_.push_back(std::move(action)); }
  /// Opens `path` (ViewerState::open_file) during the next frame, as the Files panel's Open
  /// button does: failures become the error popup.
  void request_open(const std::string& path);
  /// Requests a PNG of the next frame (UI included) written atomically to `path`.
  void request_screenshot(const std::string& path) { screenshot_path_ = path; }
  /// Hides (false) or shows the panels; without them frames show only the 3D view.
  void set_ui_visible(bool visible);
  /// Message of the last error shown in the popup ("" if none).
  const std::string& last_error() const { return error_; }
  /// Errors reported so far (each opens the popup).
  int error_count() const { return error_count_; }
  /// Whether the last frame drew the error popup.
  bool error_popup_open() const { return error_popup_open_; }
  /// Where the last frame's UI-thread CPU went.
  const FrameCpu& frame_cpu() const { return frame_cpu_; }
  /// Renderer uploads so far, the view thread's included (scrubbing must add none).
  int64_t upload_count() const;

  /// Draws the 3D view on a render::ViewThread (true) or on this thread (false, the default).
  /// With the thread, a frame hands the view to it and shows the newest image it has finished,
  /// so this thread's CPU per frame does not depend on what the view draws (a software
  /// rasteriser runs its vertex stage on the thread that draws); the view may then lag the
  /// panels by the time one image takes. Screenshots wait for the image of their own frame.
  /// Throws Error if the thread's context cannot be created (the viewer stays as it was).
  void set_view_thread(bool on);
  bool view_thread() const { return view_thread_ != nullptr; }
  /// With the view thread: blocks until the view of the last frame is drawn, so that the next
  /// frame shows it (tests, screenshots). Without: returns at once.
  void wait_for_view();
  /// Images the view thread has drawn (0 without it).
  int64_t view_images() const;

 private:
  void sync_layout();
  void handle_input();
  void draw_panels(Actions& actions);
  void draw_viewport_captions(const std::vector<Viewport>& viewports);
  void draw_error_popup();
  bool section(const char* label, Panel panel, bool default_open);
  void apply(Actions& actions);
  void render_view(const std::vector<Viewport>& viewports);
  void hand_view_to_thread(const std::vector<Viewport>& viewports, bool wait);
  void report(const std::exception& e);

  render::GlContext& context_;
  Platform& platform_;
  ViewerState state_;
  render::Renderer renderer_;
  ImGuiRenderer imgui_;
  PanelFields fields_;
  std::map<Panel, bool> open_requests_;
  bool ui_visible_ = true;
  std::string error_;
  bool error_pending_ = false;
  int error_count_ = 0;
  bool error_popup_open_ = false;
  std::string screenshot_path_;
  std::vector<Action> posted_;
  FrameCpu frame_cpu_;
  std::unique_ptr<render::ViewThread> view_thread_;
  void* view_texture_ = nullptr;  // the view thread's newest image, once one was shown
  double view_upload_ms_ = 0.0;   // CPU of this frame's image upload (counted as GL time)
  // Mouse drag in the 3D view: press position and whether it moved (a click picks).
  bool dragging_ = false;
  float drag_distance_ = 0.0f;
};

}  // namespace dynscope::app::viewer
