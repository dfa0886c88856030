// A checkpoint loaded behind a torch-free interface: one-step predictions for rollouts.
#pragma once

#include <memory>
#include <string>

#include "engine/model/checkpoint_info.h"
#include "engine/rollout/rollout_runner.h"

namespace dynscope {

/// A loaded model. The predictor holds the model; copies share it (not thread-safe).
struct LoadedModel {
  std::string checkpoint_path;
  ModelConfig config;
  std::string config_json;  ///< ModelConfig::to_json() of the loaded model.
  StepPredictor predict;    ///< p̂(t+1) from a state; throws ValueError on a bad state.
};

/// Loads `checkpoint_path` (load_checkpoint) in evaluation mode on the CPU. Throws IoError for a
/// missing or foreign file, FormatError or Error for a config/weights mismatch; LibTorch errors
/// are rethrown as dynscope Error naming the file.
LoadedModel load_model(const std::string& checkpoint_path);

/// Sets LibTorch's intra-op thread count (`threads` >= 1; 0 leaves the default). Throws
/// ValueError for a count outside [0, kMaxComputeThreads].
void set_torch_threads(int threads);

}  // namespace dynscope
