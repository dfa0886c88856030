// ViewerState: documents, view, timeline, checkpoint and ticketed background jobs.
#include "app/viewer/viewer_state.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "app/viewer/viewports.h"
#include "engine/core/error.h"
#include "engine/io/mesh_import.h"
#include "engine/io/rollout_file.h"
#include "engine/io/scene_file.h"
#include "engine/io/trace_file.h"
#include "engine/model/model_config.h"
#include "engine/rollout/level_view.h"
#include "engine/rollout/rollout_runner.h"
#include "engine/rollout/state_history.h"
#include "render/batch_render.h"

namespace dynscope::app::viewer {
namespace {

std::string file_name(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

// The scene a rollout started from (find_rollout_scene), or none when it is not found;
// a scene that exists but cannot be read throws, naming it.
std::optional<Scene> rollout_scene(const Rollout& rollout, const std::string& rollout_path) {
  const std::string path = find_rollout_scene(rollout, rollout_path);
  if (path.empty()) return std::nullopt;
  return read_scene(path);
}

}  // namespace

ViewerState::ViewerState(ModelServices* services) : services_(services) {
  if (services_) cache_ = std::make_shared<ModelCache>(*services_);
  view_.layers.level_points = true;
}

ViewerState::~ViewerState() { cancel_jobs(); }

void ViewerState::replaced() {
  ++generation_;
  cancel_jobs();
  drawn_pick_ = Selection{};
  selection_marker_.reset();
  explanation_.reset();
  attribution_ = render::PointAttribution{};
  attribution_series_.reset();
}

void ViewerState::cancel_jobs() {
  // A cancelled job's thread may still run: it is kept (and reaped once done) so the UI thread
  // never waits for it, and its result is never installed.
  if (rollout_job_) {
    rollout_job_->cancel();
    retired_rollouts_.push_back(std::move(rollout_job_));
  }
  if (trace_job_) {
    trace_job_->cancel();
    retired_traces_.push_back(std::move(trace_job_));
  }
  if (explain_job_) {
    explain_job_->cancel();
    retired_explains_.push_back(std::move(explain_job_));
  }
  retire_level_job();
  rollout_input_ = RolloutJobInput{};
}

void ViewerState::reap_retired() {
  auto reap = [this](auto& jobs) {
    for (auto it = jobs.begin(); it != jobs.end();) {
      if (!(*it)->done()) {
        ++it;
        continue;
      }
      ++dropped_;
      it = jobs.erase(it);
    }
  };
  reap(retired_rollouts_);
  reap(retired_traces_);
  reap(retired_explains_);
  reap(retired_levels_);
}

const SceneDocument& ViewerState::document() const {
  if (!doc_) throw ValueError("scene", "no scene is loaded");
  return *doc_;
}

void ViewerState::open_scene(const std::string& path) { set_scene(read_scene(path), path); }

void ViewerState::set_scene(const Scene& scene, const std::string& path) {
  scene.validate();
  auto doc = std::make_unique<SceneDocument>();
  doc->path = path;
  doc->scene = scene;
  render::ViewSpec build = view_;
  build.layers.level_points = true;
  build.picked_point = -1;
  build.frame = 0;
  build.level = 0;
  doc->data = std::make_unique<render::SceneRenderData>(doc->scene, build);
  doc->contact_distance = contact_distances(doc->scene, doc->data->cloud());
  replaced();
  doc_ = std::move(doc);
  data_stale_ = false;
  level_view_failed_ = -1;
  rollout_.reset();
  compare_.reset();
  trace_.reset();
  trace_data_.reset();
  trace_from_file_ = false;
  trace_failed_ = TraceWant{};
  view_.layers.level_points = true;
  view_.frame = 0;
  view_.picked_point = -1;
  timeline_ = Timeline{};
  view_.camera.fit = true;
  fit_camera();
}

int ViewerState::num_frames() const {
  if (rollout_) return rollout_->num_frames();
  return doc_ ? doc_->scene.num_frames() : 0;
}

double ViewerState::frame_dt_s() const {
  if (rollout_) return rollout_->rollout.dt_s;
  return doc_ ? doc_->scene.dt_s : 0.0;
}

int ViewerState::observed_frames() const {
  return rollout_ ? rollout_->rollout.observed_frames : RolloutOptions{}.observed_frames;
}

void ViewerState::set_frame(int frame) {
  if (num_frames() == 0) return;
  const int clamped = std::clamp(frame, 0, num_frames() - 1);
  const int traced = trace_frame();
  view_.frame = clamped;
  // Level points of a model trace are the hierarchy of one frame; only level-0 points (the
  // model's points) keep their index from frame to frame.
  if (trace_frame() != traced && view_.level > 0 && !trace_from_file_) view_.picked_point = -1;
  ensure_level_view(/*in_background=*/true);
}

void ViewerState::select_point(int point) {
  if (point >= 0) {
    ensure_render_data();
    const render::SceneRenderData* data = active_data();
    const int n = data ? data->level_size() : 0;
    if (point >= n) {
      throw ValueError("picked_point", std::to_string(point) + " is outside the " +
                                           std::to_string(n) + " points of level " +
                                           std::to_string(view_.level));
    }
    view_.layers.neighborhoods = true;
    show_panel(Panel::kInspector);
  }
  drawn_pick_ = Selection{};
  selection_marker_.reset();
  view_.picked_point = std::max(point, -1);
  ensure_level_view(/*in_background=*/false);
}

void ViewerState::select(PickSet set, int point) {
  if (set == PickSet::kNone || point < 0) {
    select_point(-1);
    return;
  }
  if (set == PickSet::kLevel) {
    select_point(point);
    return;
  }
  const RolloutDocument* doc = set == PickSet::kCompared ? compare_.get() : rollout_.get();
  if (!doc) {
    throw ValueError("pick", std::string("no ") + pick_set_name(set) + " is shown");
  }
  const int n = static_cast<int>(doc->rollout.num_points());
  if (point >= n) {
    throw ValueError("picked_point", std::to_string(point) + " is outside the " +
                                         std::to_string(n) + " points of the " +
                                         pick_set_name(set));
  }
  view_.picked_point = -1;
  drawn_pick_ = {set, point, view_.frame};
  // The marker: the picked point and the same point of the other set, every frame, built once.
  const render::PointSeries& picked =
      set == PickSet::kTruth ? *doc->series.truth : *doc->series.prediction;
  const render::PointSeries& other =
      set == PickSet::kTruth ? *doc->series.prediction : *doc->series.truth;
  auto marker = std::make_shared<render::PointSeries>();
  marker->num_frames = std::min(picked.num_frames, other.num_frames);
  marker->num_points = 2;
  for (int f = 0; f < marker->num_frames; ++f) {
    for (const render::PointSeries* s : {&picked, &other}) {
      const Vec3 p = s->position(f, point);
      marker->positions.insert(
          marker->positions.end(),
          {static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())});
    }
  }
  selection_marker_ = std::move(marker);
  show_panel(Panel::kInspector);
}

Selection ViewerState::selection() const {
  if (!drawn_pick_.empty()) return drawn_pick_;
  if (view_.picked_point >= 0) return {PickSet::kLevel, view_.picked_point, level_frame()};
  return {};
}

void ViewerState::set_level(int level) {
  const int last = num_levels() - 1;
  if (level < 0 || level > last) {
    throw ValueError("level", std::to_string(level) + " is outside 0.." + std::to_string(last));
  }
  if (level == view_.level) return;
  view_.level = level;
  view_.picked_point = -1;  // indices of another level's points mean nothing here
  ensure_render_data();
}

void ViewerState::open_file(const std::string& path) {
  if (is_rollout_file(path)) {
    open_rollout(path);
  } else if (is_trace_file(path)) {
    open_trace(path);
  } else if (!is_hdf5_file(path) && std::filesystem::is_regular_file(path) && is_mesh_file(path)) {
    // A mesh alone has no motion to show: say what to do with it instead of "not HDF5".
    throw IoError(path,
                  "is a mesh, not a scene, rollout or trace; make scenes with it "
                  "(`dynscope generate --scenario NAME --meshes DIR`) or inspect it "
                  "(`dynscope info " +
                      path + "`)");
  } else {
    open_scene(path);
  }
}

void ViewerState::open_rollout(const std::string& path) {
  const Rollout rollout = read_rollout(path);
  try {
    rollout.validate();
  } catch (const Error& e) {
    throw ValueError("rollout", path + ": " + e.what());
  }
  if (rollout.num_frames() == 0) throw FormatError(path, "positions", "the rollout has no frames");
  const std::optional<Scene> scene = rollout_scene(rollout, path);
  if (scene) set_scene(*scene, rollout.scene_path);
  set_rollout(rollout, path, scene ? &*scene : nullptr);
}

void ViewerState::set_rollout(const Rollout& rollout, const std::string& label,
                              const Scene* scene) {
  std::unique_ptr<RolloutDocument> doc = make_rollout_document(rollout, label, scene);
  replaced();
  if (!scene) {
    // No scene to go with it: scene panels and level layers have nothing to read.
    doc_.reset();
    trace_.reset();
    trace_data_.reset();
  }
  rollout_ = std::move(doc);
  compare_.reset();
  // One voxel of mean error: the points have drifted by their own spacing.
  error_threshold_ =
      rollout.sampling_voxel > 0 ? rollout.sampling_voxel : 0.5 * rollout_->max_error();
  const render::ViewLayers defaults = render::default_rollout_layers();
  view_.layers.error = defaults.error;
  view_.layers.level_points = false;
  view_.layers.voxels = false;
  view_.layers.neighborhoods = false;
  view_.layers.ground_truth = false;
  view_.picked_point = -1;
  view_.frame = std::min(view_.frame, rollout_->num_frames() - 1);
  if (rollout_mode_ == RolloutMode::kSideBySide) rollout_mode_ = RolloutMode::kGhost;
  timeline_ = Timeline{};
  fit_camera();
  show_panel(Panel::kRollout);
}

void ViewerState::set_compared_rollout(const Rollout& other, const std::string& label) {
  if (!rollout_) throw ValueError("compared rollout", "no rollout is shown to compare with");
  if (other.num_frames() < rollout_->num_frames()) {
    throw ValueError("compared rollout", label + " has " + std::to_string(other.num_frames()) +
                                             " frames, the shown rollout " +
                                             std::to_string(rollout_->num_frames()));
  }
  compare_ = make_rollout_document(other, label, rollout_->scene ? &*rollout_->scene : nullptr);
  if (drawn_pick_.set == PickSet::kCompared) {
    drawn_pick_ = Selection{};
    selection_marker_.reset();
  }
  fit_camera();
}

const RolloutDocument& ViewerState::rollout() const {
  if (!rollout_) throw ValueError("rollout", "no rollout is shown");
  return *rollout_;
}

void ViewerState::set_rollout_mode(RolloutMode mode) {
  const bool refit =
      (mode == RolloutMode::kSideBySide) != (rollout_mode_ == RolloutMode::kSideBySide);
  rollout_mode_ = mode;
  if (refit) fit_camera();
}

int ViewerState::jump_to_error_threshold() {
  if (!rollout_) return -1;
  const int f = first_frame_over(rollout_->rollout.point_error, error_threshold_);
  if (f >= 0) set_frame(f);
  return f;
}

void ViewerState::set_checkpoint(const std::string& checkpoint) {
  if (!checkpoint.empty() && services_ == nullptr) {
    throw ValueError("checkpoint", "this viewer has no model services to run " + checkpoint);
  }
  replaced();
  checkpoint_ = checkpoint;
  // Only the models in use stay loaded (a running job keeps its own alive until it ends).
  if (cache_) cache_->forget_except({checkpoint_, compare_checkpoint_});
  trace_.reset();
  trace_data_.reset();
  trace_from_file_ = false;
  trace_failed_ = TraceWant{};
  view_.picked_point = -1;
  if (!checkpoint.empty()) view_.layers.level_points = true;
}

void ViewerState::open_trace(const std::string& path) {
  auto trace = std::make_shared<const ModelTrace>(read_trace(path));
  if (!doc_ || rollout_) {
    if (trace->scene_path.empty() || !std::filesystem::is_regular_file(trace->scene_path)) {
      throw IoError(path, "the trace's scene file '" + trace->scene_path +
                              "' cannot be found; open the scene first");
    }
    open_scene(trace->scene_path);
  }
  // A trace of another scene (or of another frame's objects) would draw neighbourhoods the
  // model never saw on this scene.
  check_trace_matches_scene(*trace, doc_->scene, path);
  replaced();
  checkpoint_.clear();
  const int level = std::min(view_.level, static_cast<int>(trace->levels.size()) - 1);
  view_.level = std::max(level, 0);
  ensure_render_data();
  install_trace(trace, view_.level, -1,
                truth_levels_of(*trace, rollout_ ? &rollout_->rollout : nullptr));
  trace_from_file_ = true;
  view_.frame = trace->frame;
  view_.picked_point = -1;
  view_.layers.level_points = true;
  show_panel(Panel::kLevels);
}

void ViewerState::start_rollouts(const std::string& compare) {
  if (!services_ || checkpoint_.empty()) {
    throw ValueError("rollout", "a checkpoint is needed (--checkpoint, or Model > Use)");
  }
  if (!doc_) throw ValueError("rollout", "no scene is loaded");
  const int observed = observed_frames();
  std::vector<RolloutRequest> requests = {{checkpoint_, doc_->scene, doc_->path, observed}};
  if (!compare.empty()) requests.push_back({compare, doc_->scene, doc_->path, observed});
  compare_checkpoint_ = compare;
  rollout_input_ = RolloutJobInput{};
  rollout_input_.scene = doc_->scene;
  start_rollout_job(compare.empty() ? "rollout" : "rollouts", std::move(requests), std::nullopt);
}

void ViewerState::start_what_if(const ObjectEdit& edit) {
  if (!services_ || checkpoint_.empty()) {
    throw ValueError("what-if", "a checkpoint is needed (--checkpoint, or Model > Use)");
  }
  if (!doc_) throw ValueError("what-if", "no scene is loaded");
  // The original is the shown rollout when it is this checkpoint's on this scene.
  const bool have_original =
      rollout_ && rollout_->rollout.checkpoint_path == checkpoint_ && rollout_->scene && !compare_;
  const int observed = observed_frames();
  Scene edited = apply_initial_state_edit(doc_->scene, edit, observed - 1);
  std::vector<RolloutRequest> requests;
  if (!have_original) requests.push_back({checkpoint_, doc_->scene, doc_->path, observed});
  requests.push_back({checkpoint_, edited, doc_->path, observed});
  RolloutJobInput input;
  input.scene = doc_->scene;
  if (have_original) input.original = rollout_->rollout;
  rollout_input_ = std::move(input);
  start_rollout_job("what-if", std::move(requests), std::move(edited));
}

void ViewerState::start_rollout_job(const std::string& label, std::vector<RolloutRequest> requests,
                                    std::optional<Scene> what_if_scene) {
  if (rollout_job_) throw ValueError("rollout", "a " + rollout_job_->label() + " is running");
  int64_t total = 0;
  for (const RolloutRequest& r : requests) {
    total += std::max(0, r.scene.num_frames() - r.observed_frames);
  }
  rollout_input_.what_if_scene = std::move(what_if_scene);
  ModelServices* services = services_;
  std::shared_ptr<ModelCache> cache = cache_;
  rollout_job_ = std::make_unique<BackgroundJob<std::vector<Rollout>>>(
      label, ticket(), total,
      [services, cache, requests = std::move(requests)](JobControl& control) {
        std::vector<Rollout> out;
        for (const RolloutRequest& r : requests) {
          control.check();
          const std::shared_ptr<LoadedCheckpoint> model = cache->get(r.checkpoint);
          out.push_back(services->rollout(*model, r, control));
        }
        return out;
      });
}

void ViewerState::update_jobs() {
  reap_retired();
  if (rollout_job_ && rollout_job_->done()) {
    const std::unique_ptr<BackgroundJob<std::vector<Rollout>>> job = std::move(rollout_job_);
    RolloutJobInput input = std::move(rollout_input_);
    rollout_input_ = RolloutJobInput{};
    if (job->ticket() != ticket() || job->cancelled()) {
      ++dropped_;  // cannot happen while replaced() retires jobs; kept as the rule's last guard
    } else {
      std::vector<Rollout> results = job->take();
      if (input.what_if_scene) {
        const Rollout original = input.original ? *input.original : results.front();
        const Scene edited = std::move(*input.what_if_scene);
        set_rollout(results.back(), "what-if of " + file_name(checkpoint_), &edited);
        set_compared_rollout(original, "original");
      } else {
        const Scene* scene = input.scene ? &*input.scene : nullptr;
        set_rollout(results[0], "rollout of " + file_name(results[0].checkpoint_path), scene);
        if (results.size() > 1) {
          set_compared_rollout(results[1], "rollout of " + file_name(results[1].checkpoint_path));
        }
      }
      if (compare_) set_rollout_mode(RolloutMode::kSideBySide);
    }
  }
  if (trace_job_ && trace_job_->done()) {
    const std::unique_ptr<BackgroundJob<TraceJobResult>> job = std::move(trace_job_);
    if (job->ticket() != ticket() || job->cancelled() || !doc_) {
      ++dropped_;
    } else {
      try {
        TraceJobResult result = job->take();
        install_trace(std::make_shared<const ModelTrace>(std::move(result.trace)),
                      trace_request_.level, trace_request_.picked, std::move(result.truth_levels));
      } catch (...) {
        trace_failed_ = trace_request_;
        throw;
      }
    }
  }
  update_explain_job();
  take_level_job();
  if (trace_from_file_ && trace_ && trace_level_ != view_.level &&
      view_.level < static_cast<int>(trace_->levels.size())) {
    install_trace(trace_, view_.level, -1, truth_levels_);
  }
  if (checkpoint_.empty() || !services_ || !doc_ || trace_job_ ||
      trace_frame() >= doc_->scene.num_frames()) {
    return;
  }
  const TraceWant want{trace_frame(), view_.level, view_.picked_point, traces_rollout()};
  const bool have = trace_ && trace_->frame == want.frame && trace_level_ == want.level &&
                    trace_picked_ == want.picked &&
                    (trace_->source == kTraceSourceRollout) == want.rollout;
  if (have || trace_failed_ == want) return;
  trace_request_ = want;
  TraceRequest request{checkpoint_, std::make_shared<const Scene>(doc_->scene),
                       doc_->path,  want.frame,
                       want.level,  want.picked};
  if (want.rollout) {
    request.rollout = std::make_shared<const Rollout>(rollout_->rollout);
    request.rollout_path = rollout_->path;
  }
  ModelServices* services = services_;
  std::shared_ptr<ModelCache> cache = cache_;
  trace_job_ = std::make_unique<BackgroundJob<TraceJobResult>>(
      "trace", ticket(), 1, [services, cache, request = std::move(request)](JobControl& control) {
        const std::shared_ptr<LoadedCheckpoint> model = cache->get(request.checkpoint);
        control.check();
        TraceJobResult result{services->trace(*model, request, control), nullptr};
        control.check();
        result.truth_levels = truth_levels_of(result.trace, request.rollout.get());
        return result;
      });
}

}  // namespace dynscope::app::viewer
