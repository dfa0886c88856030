// Checkpoint-backed step predictor.
#include "engine/rollout/model_predictor.h"

#include <c10/util/Exception.h>
#include <torch/utils.h>

#include "engine/core/error.h"
#include "engine/core/threads.h"
#include "engine/model/checkpoint.h"

namespace dynscope {

LoadedModel load_model(const std::string& checkpoint_path) {
  DynamicsModel model{nullptr};
  try {
    model = load_checkpoint(checkpoint_path);
  } catch (const c10::Error& e) {
    throw IoError(checkpoint_path,
                  std::string("cannot load checkpoint: ") + e.what_without_backtrace());
  }
  model->eval();
  LoadedModel out;
  out.checkpoint_path = checkpoint_path;
  out.config = model->config();
  out.config_json = out.config.to_json();
  out.predict = [model](const PointState& state) mutable {
    try {
      return model->predict_next(state);
    } catch (const c10::Error& e) {
      throw Error(std::string("model forward failed: ") + e.what_without_backtrace());
    }
  };
  return out;
}

void set_torch_threads(int threads) {
  // Far more threads than cores never finishes on a busy machine; a count above the compute
  // budget's bound is a typing error.
  if (threads < 0 || threads > kMaxComputeThreads) {
    throw ValueError("threads", "must be in [0, " + std::to_string(kMaxComputeThreads) +
                                    "] (0: LibTorch's default), got " + std::to_string(threads));
  }
  if (threads > 0) torch::set_num_threads(threads);
}

}  // namespace dynscope
