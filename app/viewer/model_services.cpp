// ModelCache: one loaded model per checkpoint for the viewer's jobs.
#include "app/viewer/model_services.h"

namespace dynscope::app::viewer {

std::shared_ptr<LoadedCheckpoint> ModelCache::get(const std::string& checkpoint) {
  std::lock_guard<std::mutex> load_lock(load_mutex_);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = models_.find(checkpoint);
    if (it != models_.end()) return it->second;
  }
  std::shared_ptr<LoadedCheckpoint> model = services_.load(checkpoint);
  std::lock_guard<std::mutex> lock(mutex_);
  ++loads_;
  models_[checkpoint] = model;
  return model;
}

void ModelCache::forget_except(const std::set<std::string>& keep) {
  std::lock_guard<std::mutex> lock(mutex_);
  for (auto it = models_.begin(); it != models_.end();) {
    it = keep.count(it->first) ? std::next(it) : models_.erase(it);
  }
}

int ModelCache::loads() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return loads_;
}

size_t ModelCache::size() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return models_.size();
}

}  // namespace dynscope::app::viewer
