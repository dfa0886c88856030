// ViewerApp: the interactive viewer's state, panels, input handling and drawing, one frame at a
// time.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "app/viewer/imgui_renderer.h"
#include "app/viewer/platform.h"
#include "app/viewer/scene_inspection.h"
#include "engine/scene/scene.h"
#include "render/gl_context.h"
#include "render/renderer.h"
#include "render/scene_adapter.h"
#include "render/view_spec.h"

namespace dynscope::app::viewer {

/// Collapsible sections of the side panel.
enum class Panel { kFiles, kDisplay, kObjects, kContacts, kLevels, kInspector };

/// Playback state of the timeline.
struct Timeline {
  bool playing = false;
  float speed = 1.0f;  ///< Multiple of real time (scene dt_s per frame).
  bool loop = true;
  double accumulated_s = 0.0;  ///< Play time not yet turned into a frame step.
};

/// A loaded scene and what is derived from it once (the GPU-facing SceneRenderData for the view's
/// level, contact distances). A rollout would add its ComparisonSeries and error scalars beside
/// the scene here, so panels and the viewport read both from one place.
struct SceneDocument {
  std::string path;
  Scene scene;
  std::unique_ptr<render::SceneRenderData> data;
  std::vector<double> contact_distance;  ///< `[T]` target–zone minimum distance, or empty.
  std::map<int, std::vector<LevelCount>> level_counts;  ///< Model hierarchy per frame (cache).
};

/// The viewer: owns the scene document, view spec (camera, layers, level, picked point), timeline
/// and the two drawers (Renderer for the 3D view, ImGuiRenderer for the panels). The 3D view fills
/// the framebuffer behind the panels, so picking and Camera::project use full-window pixels.
/// Errors from user actions are shown in a popup and never escape frame().
class ViewerApp {
 public:
  /// Draws into `context` (made current) with input from `platform`; an ImGuiSession must exist.
  /// Throws Error if GL setup fails.
  ViewerApp(render::GlContext& context, Platform& platform);
  ~ViewerApp();
  ViewerApp(const ViewerApp&) = delete;
  ViewerApp& operator=(const ViewerApp&) = delete;

  /// Reads a scene file and shows it (frame 0, camera fitted unless the view fixes it). Throws
  /// IoError/FormatError/ValueError naming the file; the previous scene stays on failure.
  void open_scene(const std::string& path);
  /// Shows `scene` (validated; throws ValueError) labelled `path`.
  void set_scene(const Scene& scene, const std::string& path);
  /// Applies a view spec file (camera, layers, level, frame, picked point). Throws IoError or
  /// FormatError naming the file; the current view stays on failure.
  void open_view(const std::string& path);
  /// Applies `view` (validated; throws ValueError); a fitted camera is resolved against the scene.
  void set_view(const render::ViewSpec& view);
  /// Writes the current view (explicit camera, window size) as JSON; throws IoError naming `path`.
  void save_view(const std::string& path) const;
  /// The current view: what save_view writes.
  render::ViewSpec current_view() const;

  /// Runs one frame: platform input, panels, 3D view, UI on top, pending screenshot, swap.
  void frame();
  /// Reads the framebuffer of the last frame (RGBA, rows top to bottom).
  render::Image read_pixels();

  bool has_scene() const { return doc_ != nullptr; }
  /// The shown scene document; throws ValueError if none is loaded.
  const SceneDocument& document() const;
  int current_frame() const { return view_.frame; }
  /// Moves the timeline to `frame` (clamped to the scene); no upload happens.
  void set_frame(int frame);
  /// Picks the level point at pixel (x, y) as a click would; returns whether a point was hit.
  bool pick(int x, int y);
  /// Selected level point or -1.
  int selected_point() const { return view_.picked_point; }
  /// Selects level point `point` (-1 clears); throws ValueError if out of range.
  void select_point(int point);
  /// Sets the U-Net level shown (0..3) and clears the selection; throws ValueError if out of range.
  void set_level(int level);
  /// Layers drawn in the 3D view (same meaning as in a view spec).
  render::ViewLayers& layers() { return view_.layers; }
  const render::Camera& camera() const { return view_.camera.camera; }
  /// Opens `panel`'s section on the next frame.
  void show_panel(Panel panel);
  /// Hides (false) or shows the panels; without them frames show only the 3D view.
  void set_ui_visible(bool visible) { ui_visible_ = visible; }
  /// Message of the last error shown in the popup ("" if none).
  const std::string& last_error() const { return error_; }
  /// Renderer uploads so far (scrubbing must add none).
  int64_t upload_count() const { return renderer_.upload_count(); }
  /// Requests a PNG of the next frame (UI included) written atomically to `path`.
  void request_screenshot(const std::string& path) { screenshot_path_ = path; }

 private:
  void ensure_render_data();
  void fit_camera();
  void handle_input();
  void advance_playback(float dt_s);
  void draw_panels();
  void draw_files_section();
  void draw_display_section();
  void draw_objects_section();
  void draw_contacts_section();
  void draw_levels_section();
  void draw_inspector_section();
  void draw_timeline();
  void draw_error_popup();
  bool section(const char* label, Panel panel, bool default_open);
  void report(const std::exception& e);
  render::RenderScene pick_scene() const;

  render::GlContext& context_;
  Platform& platform_;
  render::Renderer renderer_;
  ImGuiRenderer imgui_;
  std::unique_ptr<SceneDocument> doc_;
  render::ViewSpec view_;
  int data_level_ = -1;  ///< Level doc_->data was built for.
  Timeline timeline_;
  bool ui_visible_ = true;
  std::map<Panel, bool> open_requests_;
  std::string error_;
  bool error_pending_ = false;
  std::string screenshot_path_;
  // Text fields of the Files section.
  std::string scene_field_;
  std::string view_field_ = "view.json";
  std::string screenshot_field_ = "screenshot.png";
  // Mouse drag in the 3D view: press position and whether it moved (a click picks).
  bool dragging_ = false;
  float drag_distance_ = 0.0f;
};

}  // namespace dynscope::app::viewer
