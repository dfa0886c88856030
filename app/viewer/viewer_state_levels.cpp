// ViewerState: the levels and traces the level browser, inspector and picking read (the
// model's trace of the current frame, or without a checkpoint its level view).
#include <algorithm>

#include "app/viewer/viewer_state.h"
#include "engine/core/error.h"
#include "engine/model/hierarchy.h"
#include "engine/model/model_config.h"
#include "engine/rollout/level_view.h"
#include "engine/rollout/state_history.h"

namespace dynscope::app::viewer {

int ViewerState::trace_frame() const {
  if (checkpoint_.empty()) return view_.frame;
  if (traces_rollout()) {
    // The pass at t produced the rollout's frame t+1: from the first predicted frame's to the last.
    const Rollout& r = rollout_->rollout;
    return std::clamp(view_.frame, first_rollout_trace_frame(r.observed_frames),
                      std::max(r.num_frames() - 2, first_rollout_trace_frame(r.observed_frames)));
  }
  return std::max(view_.frame, kFirstTraceableFrame);
}

bool ViewerState::traces_rollout() const {
  return trace_input_ == TraceInput::kPrediction && rollout_ && doc_ && !trace_from_file_ &&
         !checkpoint_.empty() &&
         rollout_->num_frames() - 2 >= first_rollout_trace_frame(rollout_->rollout.observed_frames);
}

void ViewerState::set_trace_input(TraceInput input) {
  if (input == trace_input_) return;
  trace_input_ = input;
  if (view_.level > 0) view_.picked_point = -1;  // the other input has other level points
}

int ViewerState::level_frame() const { return shown_trace() ? trace_->frame : view_.frame; }

int ViewerState::num_levels() const {
  // The model's own count: the trace's levels, else those of the config whose hierarchy the level
  // browser shows for this scene.
  if (trace_) return static_cast<int>(trace_->levels.size());
  if (doc_) return level_view_config(doc_->scene).levels;
  return ModelConfig{}.levels;
}

std::vector<LevelCount> ViewerState::level_counts() const {
  if (const ModelTrace* trace = shown_trace()) return trace_level_counts(*trace);
  return {};
}

std::shared_ptr<const ModelTrace> truth_levels_of(const ModelTrace& trace, const Rollout* rollout) {
  if (trace.source != kTraceSourceRollout || !rollout || trace.frame < 0 ||
      trace.frame >= rollout->num_frames()) {
    return nullptr;
  }
  // The same model's hierarchy on the ground truth of the frame, to compare the lists with.
  const ModelConfig config = ModelConfig::from_json(trace.model_config, "trace");
  const Points& truth = rollout->truth[static_cast<size_t>(trace.frame)];
  return std::make_shared<const ModelTrace>(
      hierarchy_trace(build_model_hierarchy(truth, rollout->object_ids, rollout->faces, config),
                      rollout->faces, trace.frame, config));
}

void ViewerState::install_trace(std::shared_ptr<const ModelTrace> trace, int level, int picked,
                                std::shared_ptr<const ModelTrace> truth_levels) {
  render::ViewSpec build = view_;
  build.level = level;
  build.layers.level_points = true;
  build.layers.ground_truth = true;  // the "all points" layer stays available
  build.picked_point = -1;
  build.frame = trace->frame;
  trace_data_ = std::make_unique<render::SceneRenderData>(doc_->scene, build, trace);
  truth_levels_ = std::move(truth_levels);
  trace_ = std::move(trace);
  trace_level_ = level;
  trace_picked_ = picked;
}

const ModelTrace* ViewerState::shown_trace() const {
  if (!trace_ || !trace_data_ || trace_->frame != trace_frame() || trace_level_ != view_.level) {
    return nullptr;
  }
  // A checkpoint's trace of the other input (prediction vs truth) is not what was asked for.
  if (!checkpoint_.empty() && !trace_from_file_ &&
      (trace_->source == kTraceSourceRollout) != traces_rollout()) {
    return nullptr;
  }
  return trace_.get();
}

const render::SceneRenderData* ViewerState::active_data() const {
  if (shown_trace()) return trace_data_.get();
  return doc_ ? doc_->data.get() : nullptr;
}

void ViewerState::ensure_render_data(bool in_background) {
  if (doc_ && (!doc_->data || data_stale_)) {
    render::ViewSpec build = view_;
    build.layers.level_points = true;  // points are always prepared so they can be picked
    build.picked_point = -1;
    build.frame = 0;
    build.level = 0;
    doc_->data = std::make_unique<render::SceneRenderData>(doc_->scene, build);
    // The sampling voxel may have changed: level views are drawn anew.
    doc_->levels.reset();
    retire_level_job();
    if (trace_ && is_level_view(*trace_)) {
      trace_.reset();
      trace_data_.reset();
    }
    level_view_failed_ = -1;
  }
  data_stale_ = false;
  ensure_level_view(in_background);
}

void ViewerState::retire_level_job() {
  if (!level_job_) return;
  level_job_->cancel();
  retired_levels_.push_back(std::move(level_job_));
}

void ViewerState::take_level_job() {
  if (!level_job_ || !level_job_->done()) return;
  const std::unique_ptr<BackgroundJob<std::shared_ptr<const ModelTrace>>> job =
      std::move(level_job_);
  if (job->ticket() != ticket() || job->cancelled() || !doc_) {
    ++dropped_;
    return;
  }
  try {
    job->take();  // the view is now the one doc_->levels keeps
  } catch (...) {
    level_view_failed_ = level_job_frame_;
    view_.layers.interaction_points = false;
    throw;
  }
}

void ViewerState::ensure_level_view(bool in_background) {
  take_level_job();
  if (!doc_ || !checkpoint_.empty() || trace_from_file_ ||
      view_.frame >= doc_->scene.num_frames()) {
    return;
  }
  if (!level_view_wanted_ && view_.picked_point < 0 && !render::view_needs_levels(view_)) return;
  const ModelConfig config = render::level_view_config(doc_->scene, view_);
  if (level_view_failed_ == view_.frame &&
      (!doc_->levels || doc_->levels->config().input == config.input)) {
    return;
  }
  std::shared_ptr<const ModelTrace> levels;
  try {
    if (!doc_->levels || doc_->levels->config().input != config.input) {
      // Points of another input (mesh vertices vs samples): a selection means nothing there.
      if (doc_->levels) view_.picked_point = -1;
      retire_level_job();
      doc_->levels = render::make_level_views(doc_->scene, view_);
    }
    levels = doc_->levels->cached(view_.frame);
    if (!levels && in_background) {
      // One job at a time: while scrubbing, the next frame's starts when this one is taken.
      if (!level_job_) {
        level_job_frame_ = view_.frame;
        level_job_ = std::make_unique<BackgroundJob<std::shared_ptr<const ModelTrace>>>(
            "level view", ticket(), 1,
            [views = doc_->levels, frame = view_.frame](JobControl&) { return views->at(frame); });
      }
      return;
    }
    if (!levels) levels = doc_->levels->at(view_.frame);
  } catch (...) {
    level_view_failed_ = view_.frame;
    // Mesh input fails on a scene it cannot read (deformable objects): the layer goes off.
    view_.layers.interaction_points = false;
    throw;
  }
  level_view_wanted_ = false;
  if (trace_ == levels && trace_level_ == view_.level) return;
  install_trace(levels, view_.level, -1, nullptr);
  if (view_.picked_point >= trace_data_->level_size()) view_.picked_point = -1;
}

}  // namespace dynscope::app::viewer
