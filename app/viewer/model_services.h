// ModelServices: what the viewer asks of a trained model (rollouts, traces) behind a torch-free
// interface; `dynscope view` implements it with the engine's LibTorch code, tests with fakes.
#pragma once

#include <string>

#include "engine/core/progress.h"
#include "engine/io/trace_file.h"
#include "engine/scene/rollout.h"
#include "engine/scene/scene.h"

namespace dynscope::app::viewer {

/// One rollout the viewer wants: `checkpoint` run on `scene` (possibly an edited copy of the file
/// at `scene_path`) with `observed_frames` ground-truth frames, over all frames of the scene.
struct RolloutRequest {
  std::string checkpoint;
  Scene scene;
  std::string scene_path;
  int observed_frames = 3;
};

/// The model behind the viewer. Calls may come from a background thread (one at a time per
/// object); implementations must not touch the viewer or GL.
class ModelServices {
 public:
  virtual ~ModelServices() = default;
  /// Rolls `request.checkpoint` out on `request.scene`, advancing `progress` (may be null) once
  /// per predicted frame; scene_path and checkpoint_path of the result are filled. Throws Error
  /// (IoError naming the checkpoint, ValueError for a bad request) on failure.
  virtual Rollout rollout(const RolloutRequest& request, Progress* progress) = 0;
  /// One forward pass of `checkpoint` on `scene` at `frame` with the filter weights of level
  /// `level`'s point `picked` (-1: none), as capture_checkpoint_trace. Throws Error on failure.
  virtual ModelTrace trace(const std::string& checkpoint, const Scene& scene,
                           const std::string& scene_path, int frame, int level, int picked) = 0;
};

}  // namespace dynscope::app::viewer
