// ModelServices: what the viewer asks of a trained model (load, rollouts, traces) behind a
// torch-free interface; `dynscope view` implements it with the engine's LibTorch code, tests with
// fakes. ModelCache keeps one loaded model per checkpoint for every job that runs it.
#pragma once

#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>

#include "app/viewer/background_job.h"
#include "engine/io/trace_file.h"
#include "engine/rollout/divergence.h"
#include "engine/rollout/explain.h"
#include "engine/rollout/rollout_runner.h"
#include "engine/scene/rollout.h"
#include "engine/scene/scene.h"

namespace dynscope::app::viewer {

/// One rollout the viewer wants: `checkpoint` run on `scene` (possibly an edited copy of the file
/// at `scene_path`) with `observed_frames` ground-truth frames, over all frames of the scene.
struct RolloutRequest {
  std::string checkpoint;
  Scene scene;
  std::string scene_path;
  int observed_frames = RolloutOptions{}.observed_frames;
};

/// One trace the viewer wants: a forward pass on `scene` at `frame` with the filter weights of
/// level `level`'s point `picked` (-1: none). With `rollout` set, the pass reads the rollout's own
/// predicted frames frame−2..frame (the one that produced its frame+1), not the scene's.
struct TraceRequest {
  std::string checkpoint;
  std::shared_ptr<const Scene> scene;
  std::string scene_path;
  int frame = -1, level = -1, picked = -1;
  std::shared_ptr<const Rollout> rollout;
  std::string rollout_path;
};

/// One explanation the viewer wants: `checkpoint` on `rollout` at pass `frame` (−1: the
/// divergence) of `object` or `point` (both −1: the diverging object; see resolve_selection).
struct ExplainJobRequest {
  std::string checkpoint;
  std::shared_ptr<const Rollout> rollout;
  int frame = -1;
  int32_t object = -1;
  int point = -1;
  ExplainTarget target = ExplainTarget::kError;
};

/// What an explain job returns: the rollout's divergence and the explanation of the question.
struct RolloutExplanation {
  Divergence divergence;
  Explanation explanation;
};

/// A checkpoint loaded once (weights, config) by ModelServices::load; what it holds is the
/// implementation's. Jobs share it; implementations serialise calls on one model if needed.
class LoadedCheckpoint {
 public:
  virtual ~LoadedCheckpoint() = default;
};

/// The model behind the viewer. Calls come from background threads; implementations must not
/// touch the viewer or GL, and should poll `control` (JobControl::check) between steps.
class ModelServices {
 public:
  virtual ~ModelServices() = default;
  /// Loads `checkpoint`. Throws Error (IoError naming the file) on failure.
  virtual std::shared_ptr<LoadedCheckpoint> load(const std::string& checkpoint) = 0;
  /// Rolls `model` (loaded from request.checkpoint) out on `request.scene`, advancing
  /// control.progress() once per predicted frame; scene_path and checkpoint_path of the result are
  /// filled. Throws JobCancelled when cancelled, Error (ValueError for a bad request) on failure.
  virtual Rollout rollout(LoadedCheckpoint& model, const RolloutRequest& request,
                          JobControl& control) = 0;
  /// One forward pass of `model` as capture_checkpoint_trace. Throws JobCancelled or Error.
  virtual ModelTrace trace(LoadedCheckpoint& model, const TraceRequest& request,
                           JobControl& control) = 0;
  /// find_divergence with the model's config, then the explanation of the resolved question
  /// (RolloutExplainer). Throws JobCancelled or Error (ValueError for a bad question).
  virtual RolloutExplanation explain(LoadedCheckpoint& model, const ExplainJobRequest& request,
                                     JobControl& control) = 0;
};

/// One loaded model per checkpoint, shared by every job that runs it (thread-safe). A model is
/// loaded on first use, from the job's thread, and kept until forget_except drops it.
class ModelCache {
 public:
  /// `services` must outlive the cache.
  explicit ModelCache(ModelServices& services) : services_(services) {}
  /// The loaded model of `checkpoint` (loading it on first use, and again when the file has
  /// changed on disk since: size or modification time); throws what load throws.
  std::shared_ptr<LoadedCheckpoint> get(const std::string& checkpoint);
  /// Drops every model but those of `keep` (running jobs keep theirs alive).
  void forget_except(const std::set<std::string>& keep);
  /// ModelServices::load calls so far.
  int loads() const;
  /// Checkpoints held now.
  size_t size() const;

 private:
  ModelServices& services_;
  mutable std::mutex mutex_;
  std::mutex load_mutex_;  ///< One load at a time, so two jobs never load the same file twice.
  struct Entry {
    std::string stamp;  ///< File size and modification time when loaded ("" if unreadable).
    std::shared_ptr<LoadedCheckpoint> model;
  };
  std::map<std::string, Entry> models_;
  int loads_ = 0;
};

}  // namespace dynscope::app::viewer
