// Checkpoint-backed step predictor.
#include "engine/rollout/model_predictor.h"

#include <c10/util/Exception.h>

#include <memory>
#include <mutex>

#include "engine/core/error.h"
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
  // One hierarchy cache per loaded model, shared by its copies. A caller that finds it in use by
  // another thread builds its hierarchy without it (same result, no reuse).
  struct SharedCache {
    std::mutex mutex;
    HierarchyCache cache;
  };
  auto shared = std::make_shared<SharedCache>();
  out.predict = [model, shared](const PointState& state) mutable {
    const std::unique_lock<std::mutex> lock(shared->mutex, std::try_to_lock);
    try {
      return model->predict_next(state, lock.owns_lock() ? &shared->cache : nullptr);
    } catch (const c10::Error& e) {
      throw Error(std::string("model forward failed: ") + e.what_without_backtrace());
    }
  };
  return out;
}

}  // namespace dynscope
