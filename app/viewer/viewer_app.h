// ViewerApp: the interactive viewer's state, panels, input handling and drawing, one frame at a
// time.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "app/viewer/background_job.h"
#include "app/viewer/imgui_renderer.h"
#include "app/viewer/initial_state_edit.h"
#include "app/viewer/model_services.h"
#include "app/viewer/platform.h"
#include "app/viewer/rollout_document.h"
#include "app/viewer/scene_inspection.h"
#include "engine/scene/scene.h"
#include "render/gl_context.h"
#include "render/renderer.h"
#include "render/scene_adapter.h"
#include "render/view_spec.h"

namespace dynscope::app::viewer {

/// Collapsible sections of the side panel.
enum class Panel { kFiles, kDisplay, kRollout, kModel, kObjects, kContacts, kLevels, kInspector };

/// Playback state of the timeline.
struct Timeline {
  bool playing = false;
  float speed = 1.0f;  ///< Multiple of real time (scene dt_s per frame).
  bool loop = true;
  double accumulated_s = 0.0;  ///< Play time not yet turned into a frame step.
};

/// A loaded scene and what is derived from it once (the GPU-facing SceneRenderData for the view's
/// level, contact distances). A shown rollout lives beside it in a RolloutDocument.
struct SceneDocument {
  std::string path;
  Scene scene;
  std::unique_ptr<render::SceneRenderData> data;
  std::vector<double> contact_distance;  ///< `[T]` target–zone minimum distance, or empty.
  std::map<int, std::vector<LevelCount>> level_counts;  ///< Model hierarchy per frame (cache).
};

/// What one viewport of the 3D view draws: `scene` seen by `camera` in pixel columns [x0, x1) of
/// the window (side by side: two viewports share one camera, shifted to each one's centre).
struct Viewport {
  render::RenderScene scene;
  render::Camera camera;
  int x0 = 0, x1 = 0;
  std::string caption;  ///< Drawn at the viewport's top ("" for none).
};

/// The viewer: owns the scene document, view spec (camera, layers, level, picked point), timeline
/// and the two drawers (Renderer for the 3D view, ImGuiRenderer for the panels). The 3D view fills
/// the framebuffer behind the panels, so picking and Camera::project use full-window pixels.
/// Errors from user actions are shown in a popup and never escape frame().
class ViewerApp {
 public:
  /// Draws into `context` (made current) with input from `platform`; an ImGuiSession must exist.
  /// `services` (may be null; must outlive the app) runs the model for rollouts and traces.
  /// Throws Error if GL setup fails.
  ViewerApp(render::GlContext& context, Platform& platform, ModelServices* services = nullptr);
  ~ViewerApp();
  ViewerApp(const ViewerApp&) = delete;
  ViewerApp& operator=(const ViewerApp&) = delete;

  /// Reads a scene file and shows it (frame 0, camera fitted unless the view fixes it). Throws
  /// IoError/FormatError/ValueError naming the file; the previous scene stays on failure.
  void open_scene(const std::string& path);
  /// Shows `scene` (validated; throws ValueError) labelled `path`; closes any rollout.
  void set_scene(const Scene& scene, const std::string& path);
  /// Opens a rollout, trace or scene file by its contents (open_rollout, open_trace, open_scene);
  /// throws what they throw.
  void open_file(const std::string& path);
  /// Opens `path` (open_file) during the next frame, as the Files section's Open button does:
  /// failures become the error popup.
  void request_open(const std::string& path) { open_request_ = path; }
  /// Reads a rollout file and shows it, with the scene it names (stored path, else next to the
  /// rollout) for meshes and levels when that can be read. Throws IoError/FormatError/ValueError
  /// naming the file; the previous document stays on failure.
  void open_rollout(const std::string& path);
  /// Shows `rollout` (validated; throws ValueError) labelled `label`; `scene` (may be null) is the
  /// scene it started from. Any compared rollout is dropped.
  void set_rollout(const Rollout& rollout, const std::string& label, const Scene* scene);
  /// Shows `other` as the compared rollout (side by side or ghost); throws ValueError if it has
  /// fewer frames than the shown rollout or none is shown.
  void set_compared_rollout(const Rollout& other, const std::string& label);
  bool has_rollout() const { return rollout_ != nullptr; }
  /// The shown rollout; throws ValueError if none.
  const RolloutDocument& rollout() const;
  /// The compared rollout or null.
  const RolloutDocument* compared_rollout() const { return compare_.get(); }
  /// How the rollout is shown (refits the camera when the number of viewports changes).
  void set_rollout_mode(RolloutMode mode);
  RolloutMode rollout_mode() const { return rollout_mode_; }
  /// Mean point error above which a frame counts as diverged (scene units).
  void set_error_threshold(double threshold) { error_threshold_ = threshold; }
  double error_threshold() const { return error_threshold_; }
  /// Moves to the first frame whose mean point error exceeds the threshold; returns it, or -1
  /// (frame unchanged) when none does or no rollout is shown.
  int jump_to_error_threshold();
  /// Frames of the timeline: the rollout's when one is shown, else the scene's (0 for none).
  int num_frames() const;

  /// Uses `checkpoint` (through the ModelServices) for the level browser and inspector: its trace
  /// is captured in the background whenever frame, level or picked point change. "" stops.
  /// Throws ValueError when the app has no ModelServices.
  void set_checkpoint(const std::string& checkpoint);
  const std::string& checkpoint() const { return checkpoint_; }
  /// Reads a trace file (`dynscope trace`) and drives levels and inspector from it, at its frame;
  /// the scene it names is opened when none is shown. Throws IoError/FormatError naming the file.
  void open_trace(const std::string& path);
  /// The model trace the panels show now (at the current frame and level), or null.
  const ModelTrace* shown_trace() const;
  /// Rolls the checkpoint (and `compare`, when not empty) out on the scene in the background and
  /// shows the result(s) side by side. Throws ValueError without a scene, checkpoint or services.
  void start_rollouts(const std::string& compare);
  /// What-if: re-runs the checkpoint's rollout on the scene with `edit` applied
  /// (apply_initial_state_edit at the rollout's observed frames) in the background, and shows the
  /// new rollout against the original (which is rolled out first when none is shown). Throws
  /// ValueError without a scene, checkpoint or services, or for a bad edit.
  void start_what_if(const ObjectEdit& edit);
  /// The level data panels and picking read: built from the shown model trace, else the scene's
  /// preview levels; null without a scene.
  const render::SceneRenderData* active_data() const;
  /// True while a rollout or trace runs in the background.
  bool busy() const { return rollout_job_ != nullptr || trace_job_ != nullptr; }
  /// The viewports the 3D view draws for the current state (one, or two side by side).
  std::vector<Viewport> viewports() const;
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
  /// Selected level point (of the trace's level when a model trace is shown) or -1.
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
  void update_jobs();
  void install_trace(std::shared_ptr<const ModelTrace> trace, int level, int picked);
  void start_rollout_job(const std::string& label, std::vector<RolloutRequest> requests,
                         bool what_if);
  render::ViewSpec rollout_view(bool prediction, bool truth, bool ghost) const;
  void add_scene_layers(render::RenderScene& out) const;
  int viewport_at(int x) const;
  float timeline_height() const;
  void fit_camera();
  void handle_input();
  void advance_playback(float dt_s);
  void draw_panels();
  void draw_files_section();
  void draw_display_section();
  void draw_rollout_section();
  void draw_model_section();
  void draw_colorbar(float lo, float hi);
  void draw_error_strip();
  void draw_rollout_contacts();
  void draw_what_if();
  void draw_trace_features(const ModelTrace& trace);
  void draw_trace_mesh(const ModelTrace& trace);
  void draw_viewport_captions(const std::vector<Viewport>& viewports);
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
  ModelServices* services_;
  render::Renderer renderer_;
  ImGuiRenderer imgui_;
  std::unique_ptr<SceneDocument> doc_;
  std::unique_ptr<RolloutDocument> rollout_;
  std::unique_ptr<RolloutDocument> compare_;
  RolloutMode rollout_mode_ = RolloutMode::kGhost;
  double error_threshold_ = 0.0;
  // Model: checkpoint(s), the trace shown and the background work.
  std::string checkpoint_;
  std::string compare_field_;
  std::shared_ptr<const ModelTrace> trace_;
  bool trace_from_file_ = false;
  int trace_level_ = -1, trace_picked_ = -1;             ///< What trace_ was captured for.
  std::unique_ptr<render::SceneRenderData> trace_data_;  ///< Built from trace_ at trace_level_.
  struct TraceRequest {
    int frame = -1, level = -1, picked = -1;
  };
  TraceRequest trace_request_;  ///< What trace_job_ captures.
  TraceRequest trace_failed_;   ///< Last request that failed (not retried until it changes).
  std::unique_ptr<BackgroundJob<ModelTrace>> trace_job_;
  std::unique_ptr<BackgroundJob<std::vector<Rollout>>> rollout_job_;
  bool rollout_job_what_if_ = false;
  std::optional<Scene> what_if_scene_;  ///< Edited scene of the running what-if.
  ObjectEdit edit_;
  int edit_object_ = -1;  ///< Object index the edit fields were filled from.
  using ScissorFn = void (*)(GLint, GLint, GLsizei, GLsizei);
  ScissorFn scissor_ = nullptr;  ///< glScissor (not in render's table) for side-by-side views.
  render::ViewSpec view_;
  int data_level_ = -1;  ///< Level doc_->data was built for.
  Timeline timeline_;
  bool ui_visible_ = true;
  std::map<Panel, bool> open_requests_;
  std::string error_;
  bool error_pending_ = false;
  std::string screenshot_path_;
  std::string open_request_;
  // Text fields of the Files section.
  std::string scene_field_;
  std::string checkpoint_field_;
  std::string view_field_ = "view.json";
  std::string screenshot_field_ = "screenshot.png";
  // Mouse drag in the 3D view: press position and whether it moved (a click picks).
  bool dragging_ = false;
  float drag_distance_ = 0.0f;
};

}  // namespace dynscope::app::viewer
