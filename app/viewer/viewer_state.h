// ViewerState: the viewer's one state object (MuJoCo `simulate` style): documents, view, timeline,
// checkpoint and the ticketed background jobs; only the UI thread changes it.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "app/viewer/background_job.h"
#include "app/viewer/initial_state_edit.h"
#include "app/viewer/model_services.h"
#include "app/viewer/rollout_document.h"
#include "app/viewer/scene_inspection.h"
#include "engine/rollout/level_view.h"
#include "engine/scene/scene.h"
#include "render/scene_adapter.h"
#include "render/view_spec.h"

namespace dynscope::app::viewer {

/// Collapsible sections of the side panel.
enum class Panel {
  kFiles,
  kDisplay,
  kRollout,
  kModel,
  kExplain,
  kObjects,
  kContacts,
  kLevels,
  kInspector
};

/// Which drawn point set a click selects from.
enum class PickSet { kNone, kLevel, kPrediction, kTruth, kCompared };

/// "level points", "prediction", "truth", "compared prediction" ("" for none).
const char* pick_set_name(PickSet set);

/// What the user selected: a point of one drawn set. Level points index the shown level (of the
/// frame level_frame() gives); rollout points index the rollout's points (identity kept over
/// frames, so the selection follows scrubbing).
struct Selection {
  PickSet set = PickSet::kNone;
  int point = -1;  ///< Index into that set.
  int frame = -1;  ///< Frame it was picked at.
  bool empty() const { return set == PickSet::kNone; }
};

/// What a checkpoint's trace reads while a rollout is shown: the rollout's own predicted frames
/// (the pass that produced the next predicted frame) or the scene's ground truth at that frame.
enum class TraceInput { kPrediction, kTruth };

/// For a trace that read `rollout`'s predicted frames (a rollout-state trace): the hierarchy the
/// same model builds from the rollout's ground truth at the trace's frame, to compare the neighbour
/// lists with; null for any other trace or without a rollout. Runs the model's hierarchy
/// building (no forward pass): the viewer calls it off the UI thread, inside the trace job.
std::shared_ptr<const ModelTrace> truth_levels_of(const ModelTrace& trace, const Rollout* rollout);

/// Playback state of the timeline.
struct Timeline {
  bool playing = false;
  float speed = 1.0f;  ///< Multiple of real time (scene dt_s per frame).
  bool loop = true;
  double accumulated_s = 0.0;  ///< Play time not yet turned into a frame step.
};

/// The window the state is laid out in: its size in pixels and whether the panels are shown
/// (they cover a left column and a bottom strip; the 3D view spans the window behind them).
struct WindowLayout {
  int width = 1;
  int height = 1;
  bool ui_visible = true;
};

/// A loaded scene and what is derived from it once (the GPU-facing SceneRenderData of its sampled
/// points, contact distances, the model's level views). A shown rollout lives beside it in a
/// RolloutDocument.
struct SceneDocument {
  std::string path;
  Scene scene;
  std::unique_ptr<render::SceneRenderData> data;  ///< Level 0: the sampled points, every frame.
  std::vector<double> contact_distance;  ///< `[T]` target–zone minimum distance, or empty.
  /// The model's hierarchy at any frame when no checkpoint is used (built on first need).
  std::shared_ptr<LevelViews> levels;
};

/// Everything the viewer shows and the jobs that feed it. Replacing a document (scene, rollout,
/// trace) or the checkpoint bumps the generation: running jobs are cancelled and any result whose
/// ticket is older is dropped, never installed. Errors of user actions are thrown (ValueError,
/// IoError, FormatError naming the file or field); the state stays as it was on failure.
class ViewerState {
 public:
  /// `services` (may be null; must outlive the state) runs the model for rollouts and traces.
  explicit ViewerState(ModelServices* services = nullptr);
  ~ViewerState();
  ViewerState(const ViewerState&) = delete;
  ViewerState& operator=(const ViewerState&) = delete;

  // Documents.
  /// Reads a scene file and shows it (frame 0, camera fitted unless the view fixes it).
  void open_scene(const std::string& path);
  /// Shows `scene` (validated; throws ValueError) labelled `path`; closes any rollout.
  void set_scene(const Scene& scene, const std::string& path);
  /// Opens a rollout, trace or scene file by its contents.
  void open_file(const std::string& path);
  /// Reads a rollout file and shows it, with the scene it names when that can be read.
  void open_rollout(const std::string& path);
  /// Shows `rollout` (validated) labelled `label`; `scene` (may be null) is the scene it started
  /// from. Any compared rollout is dropped.
  void set_rollout(const Rollout& rollout, const std::string& label, const Scene* scene);
  /// Shows `other` as the compared rollout; throws ValueError if it has fewer frames than the
  /// shown rollout or none is shown.
  void set_compared_rollout(const Rollout& other, const std::string& label);
  /// Reads a trace file and drives levels and inspector from it, at its frame.
  void open_trace(const std::string& path);
  bool has_scene() const { return doc_ != nullptr; }
  bool has_rollout() const { return rollout_ != nullptr; }
  /// The shown scene document; throws ValueError if none is loaded.
  const SceneDocument& document() const;
  const SceneDocument* scene_document() const { return doc_.get(); }
  /// The shown rollout; throws ValueError if none.
  const RolloutDocument& rollout() const;
  const RolloutDocument* rollout_document() const { return rollout_.get(); }
  /// The compared rollout or null.
  const RolloutDocument* compared_rollout() const { return compare_.get(); }
  /// Frames of the timeline: the rollout's when one is shown, else the scene's (0 for none).
  int num_frames() const;
  /// Seconds per frame of what the timeline shows (0 for nothing).
  double frame_dt_s() const;
  /// Observed (ground-truth) frames before the model predicts: the rollout's, else the model's.
  int observed_frames() const;
  /// Changes each time a document or the checkpoint is replaced.
  uint64_t generation() const { return generation_; }

  // Rollout display.
  void set_rollout_mode(RolloutMode mode);
  RolloutMode rollout_mode() const { return rollout_mode_; }
  void set_error_threshold(double threshold) { error_threshold_ = threshold; }
  double error_threshold() const { return error_threshold_; }
  /// Moves to the first frame whose mean point error exceeds the threshold; returns it, or -1.
  int jump_to_error_threshold();

  // Model.
  bool has_services() const { return services_ != nullptr; }
  /// Uses `checkpoint` for the level browser and inspector ("" stops). Throws ValueError when
  /// the state has no ModelServices.
  void set_checkpoint(const std::string& checkpoint);
  const std::string& checkpoint() const { return checkpoint_; }
  /// The model trace the panels show now (at the current frame and level), or null.
  const ModelTrace* shown_trace() const;
  /// The trace held (possibly of another frame or level), or null.
  const ModelTrace* held_trace() const { return trace_.get(); }
  /// What traces read while a rollout is shown (default: its prediction). Changing it asks for a
  /// new trace.
  void set_trace_input(TraceInput input);
  TraceInput trace_input() const { return trace_input_; }
  /// True when the checkpoint's traces read the shown rollout's predicted frames.
  bool traces_rollout() const;
  /// With a rollout-state trace shown: the hierarchy the same model builds from the ground truth
  /// at that frame (no forward pass), to compare the neighbour lists with; else null.
  const ModelTrace* truth_input_levels() const { return truth_levels_.get(); }
  bool trace_from_file() const { return trace_from_file_; }
  int trace_level() const { return trace_level_; }
  /// Level point whose filter weights the held trace carries (-1 none).
  int trace_picked() const { return trace_picked_; }
  /// Rolls the checkpoint (and `compare`) out on the scene in the background.
  void start_rollouts(const std::string& compare);
  /// What-if: re-runs the checkpoint's rollout on the scene with `edit` applied in the background.
  void start_what_if(const ObjectEdit& edit);
  /// Cancels every running job (their results will be dropped).
  void cancel_jobs();
  /// True while a rollout, trace or explanation runs in the background (cancelled ones not
  /// counted).
  bool busy() const {
    return rollout_job_ != nullptr || trace_job_ != nullptr || explain_job_ != nullptr ||
           level_job_ != nullptr;
  }
  /// The running rollout job or null (label, progress).
  const BackgroundJob<std::vector<Rollout>>* rollout_job() const { return rollout_job_.get(); }
  /// Frame the running trace job captures, or -1.
  int trace_job_frame() const { return trace_job_ ? trace_request_.frame : -1; }
  /// Finished jobs whose result was dropped because their ticket was stale or they were cancelled.
  int dropped_results() const { return dropped_; }
  /// Cancelled jobs whose thread has not finished yet.
  size_t retiring_jobs() const {
    return retired_rollouts_.size() + retired_traces_.size() + retired_explains_.size() +
           retired_levels_.size();
  }
  /// The models loaded for jobs, or null without services.
  const ModelCache* model_cache() const { return cache_.get(); }
  /// Installs finished jobs of the current generation, drops stale ones and starts the trace the
  /// view needs. Throws the error of a failed job (once).
  void update_jobs();

  // Explain.
  /// Explains the shown rollout with the checkpoint in the background: its divergence and the
  /// attribution of pass `frame` (−1: the divergence) for `object` or `point` (both −1: the
  /// diverging object). When it finishes, the timeline moves to that pass and the attribution
  /// colours come on. Throws ValueError without a rollout or checkpoint, or while one runs.
  void start_explain(int frame, int32_t object, int point, ExplainTarget target);
  /// The last finished explanation of the shown rollout (dropped with it), or null.
  const RolloutExplanation* explanation() const { return explanation_.get(); }
  /// The running explanation job or null.
  const BackgroundJob<RolloutExplanation>* explain_job() const { return explain_job_.get(); }
  /// Colours the shown rollout's predicted points by the explanation's shares (when there is
  /// one); turning it on hides the level points, which would cover the predicted ones.
  void set_attribution_colors(bool on);
  bool attribution_colors() const { return attribution_colors_; }
  /// The predicted points coloured by the explanation (render::make_attribution_series) while
  /// attribution colours are on and an explanation is held; else null.
  std::shared_ptr<render::PointSeries> attribution_series() const;
  /// The explanation's shares and explained points as the renderer draws them.
  const render::PointAttribution& attribution() const { return attribution_; }
  /// Moves to pass `frame` and selects the predicted point of object `a` nearest object `b`
  /// there, with the inspector open (a contact pair of the divergence). Throws ValueError
  /// without a rollout or when an object has no points.
  void inspect_pair(int frame, int32_t a, int32_t b);

  // View.
  /// The level data panels and picking read: built from the shown trace, else the scene's
  /// preview levels; null without a scene.
  const render::SceneRenderData* active_data() const;
  /// Rebuilds the scene's level data when the level changed, and without a checkpoint installs
  /// the model's level view the view needs. `in_background`: a level view not built yet for the
  /// current frame is built by a background job (the frame loop and scrubbing: the UI thread
  /// never builds a hierarchy per frame) and installed by a later call once done; otherwise it
  /// is built now (one-off actions that read it at once: picking, a level change, a view).
  void ensure_render_data(bool in_background = false);
  const render::ViewSpec& view() const { return view_; }
  /// Layers drawn in the 3D view (same meaning as in a view spec).
  render::ViewLayers& layers() { return view_.layers; }
  const render::ViewLayers& layers() const { return view_.layers; }
  /// Applies `view` (validated; throws ValueError); a fitted camera is resolved against the scene.
  void set_view(const render::ViewSpec& view);
  /// Applies a view spec file; throws IoError or FormatError naming the file.
  void open_view(const std::string& path);
  /// Writes the current view as JSON; throws IoError naming `path`.
  void save_view(const std::string& path) const;
  /// The current view (explicit camera, window size): what save_view writes.
  render::ViewSpec current_view() const;
  int current_frame() const { return view_.frame; }
  /// Moves the timeline to `frame` (clamped); no upload happens.
  void set_frame(int frame);
  int selected_point() const { return view_.picked_point; }
  /// Selects level point `point` (-1 clears any selection); throws ValueError if out of range.
  void select_point(int point);
  /// Selects point `point` of the drawn set `set` at the current frame (kLevel: as select_point;
  /// kNone clears). Throws ValueError for a set not shown or a point outside it.
  void select(PickSet set, int point);
  /// The current selection: a rollout point, the selected level point, or empty.
  Selection selection() const;
  /// With a rollout point selected: it and the same point of the other set (the truth of a
  /// predicted point, the prediction of a true one), `[T,2]`, built once per selection; else null.
  const std::shared_ptr<render::PointSeries>& selection_marker() const { return selection_marker_; }
  /// Frame of the model trace the level browser and inspector read for the current frame: with a
  /// checkpoint, an observed frame the model cannot trace gives the first frame it can.
  int trace_frame() const;
  /// Frame the level layers are drawn at: the shown trace's frame, else the current frame.
  int level_frame() const;
  /// Sets the U-Net level shown and clears the selection; throws ValueError if out of range.
  void set_level(int level);
  /// Number of levels the browser offers (the model's, from its config or the trace).
  int num_levels() const;
  /// Points per level and object of the hierarchy shown (the trace's or level view's at its
  /// frame); empty while there is none.
  std::vector<LevelCount> level_counts() const;
  /// Asks for the model's level view at the current frame on the next ensure_render_data even
  /// when no layer needs it (the level browser's counts). Without a checkpoint the level view is
  /// the hierarchy of the scenario's preset (render::level_view_config); with one, its trace.
  void request_level_view() { level_view_wanted_ = true; }
  /// How points are drawn ("auto", "spheres", "discs"); throws ValueError for another name.
  void set_point_style(const std::string& style);
  /// Colour range of the rollout's error colouring.
  void set_error_range(bool automatic, float lo, float hi);
  render::Camera& camera() { return view_.camera.camera; }
  const render::Camera& camera() const { return view_.camera.camera; }
  /// Fits the camera to what is shown in the free part of the window (preset first when given).
  void fit_camera(const std::string& preset = "");
  /// The window the view is laid out in; refits nothing.
  void set_layout(const WindowLayout& layout) { layout_ = layout; }
  const WindowLayout& layout() const { return layout_; }
  Timeline& timeline() { return timeline_; }
  const Timeline& timeline() const { return timeline_; }
  /// Advances playback by `dt_s` seconds of display time.
  void advance_playback(float dt_s);
  /// Opens (or, with open false, closes) `panel`'s section on the next frame.
  void show_panel(Panel panel, bool open = true) { open_requests_[panel] = open; }
  /// Takes the sections asked open since the last call.
  std::map<Panel, bool> take_open_requests() { return std::move(open_requests_); }

 private:
  void replaced();
  /// Shows `trace` at `level` with `picked`'s filter weights; `truth_levels` is its
  /// truth_input_levels() (null unless it reads a rollout's prediction).
  void install_trace(std::shared_ptr<const ModelTrace> trace, int level, int picked,
                     std::shared_ptr<const ModelTrace> truth_levels);
  /// Without a checkpoint or trace file: installs the level view of the current frame when the
  /// view needs the model's hierarchy (or it was requested); see ensure_render_data.
  void ensure_level_view(bool in_background);
  /// Takes a finished level-view job: drops it if stale, rethrows its error (once); its view is
  /// then kept by the document's LevelViews for ensure_level_view to install.
  void take_level_job();
  /// Cancels the level-view job (its thread is reaped later; its result is never installed).
  void retire_level_job();
  void start_rollout_job(const std::string& label, std::vector<RolloutRequest> requests,
                         std::optional<Scene> what_if_scene);
  void reap_retired();
  /// Installs a finished explanation of the current generation (viewer_state_explain.cpp).
  void update_explain_job();
  JobTicket ticket() const { return {generation_, checkpoint_}; }

  ModelServices* services_;
  std::shared_ptr<ModelCache> cache_;
  uint64_t generation_ = 1;
  std::unique_ptr<SceneDocument> doc_;
  std::unique_ptr<RolloutDocument> rollout_;
  std::unique_ptr<RolloutDocument> compare_;
  RolloutMode rollout_mode_ = RolloutMode::kGhost;
  double error_threshold_ = 0.0;
  std::string checkpoint_;
  std::string compare_checkpoint_;
  std::shared_ptr<const ModelTrace> trace_;
  bool trace_from_file_ = false;
  int trace_level_ = -1, trace_picked_ = -1;             ///< What trace_ was captured for.
  std::unique_ptr<render::SceneRenderData> trace_data_;  ///< Built from trace_ at trace_level_.
  struct TraceWant {
    int frame = -1, level = -1, picked = -1;
    bool rollout = false;  ///< Reads the shown rollout's prediction.
    bool operator==(const TraceWant& o) const {
      return frame == o.frame && level == o.level && picked == o.picked && rollout == o.rollout;
    }
  };
  TraceInput trace_input_ = TraceInput::kPrediction;
  std::shared_ptr<const ModelTrace> truth_levels_;  ///< See truth_input_levels().
  TraceWant trace_request_;                         ///< What trace_job_ captures.
  TraceWant trace_failed_;  ///< Last request that failed (not retried until it changes).
  /// A finished rollout job's payload: results plus what installing them needs (copied at start).
  struct RolloutJobInput {
    std::optional<Scene> scene;          ///< Scene the rollouts ran on.
    std::optional<Scene> what_if_scene;  ///< Edited scene of a what-if.
    std::optional<Rollout> original;     ///< What-if: the shown original (not re-run).
  };
  RolloutJobInput rollout_input_;
  std::unique_ptr<BackgroundJob<std::vector<Rollout>>> rollout_job_;
  /// A trace job's result: the trace and, for a rollout-state trace, the hierarchy of the same
  /// frame's ground truth, both built off the UI thread.
  struct TraceJobResult {
    ModelTrace trace;
    std::shared_ptr<const ModelTrace> truth_levels;
  };
  std::unique_ptr<BackgroundJob<TraceJobResult>> trace_job_;
  std::vector<std::unique_ptr<BackgroundJob<std::vector<Rollout>>>> retired_rollouts_;
  std::vector<std::unique_ptr<BackgroundJob<TraceJobResult>>> retired_traces_;
  std::unique_ptr<BackgroundJob<std::shared_ptr<const ModelTrace>>> level_job_;
  int level_job_frame_ = -1;  ///< Frame level_job_ builds.
  std::vector<std::unique_ptr<BackgroundJob<std::shared_ptr<const ModelTrace>>>> retired_levels_;
  std::unique_ptr<BackgroundJob<RolloutExplanation>> explain_job_;
  std::vector<std::unique_ptr<BackgroundJob<RolloutExplanation>>> retired_explains_;
  std::unique_ptr<const RolloutExplanation> explanation_;
  render::PointAttribution attribution_;
  std::shared_ptr<render::PointSeries> attribution_series_;
  bool attribution_colors_ = true;
  int dropped_ = 0;
  Selection drawn_pick_;  ///< A selected rollout point (level points live in view_.picked_point).
  std::shared_ptr<render::PointSeries> selection_marker_;  ///< See selection_marker().
  render::ViewSpec view_;
  bool data_stale_ = true;          ///< doc_->data and its level views need rebuilding.
  bool level_view_wanted_ = false;  ///< See request_level_view().
  int level_view_failed_ = -1;      ///< Frame whose level view failed (not retried), or -1.
  Timeline timeline_;
  WindowLayout layout_;
  std::map<Panel, bool> open_requests_;
};

}  // namespace dynscope::app::viewer
