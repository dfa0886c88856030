// ModelCache: one loaded model per checkpoint for the viewer's jobs.
#include "app/viewer/model_services.h"

#include <filesystem>

namespace dynscope::app::viewer {
namespace {

// Size and modification time of `path` ("" when it cannot be read): a checkpoint rewritten in
// place (a resumed training run) is loaded again.
std::string file_stamp(const std::string& path) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) return "";
  const auto time = std::filesystem::last_write_time(path, ec);
  if (ec) return "";
  return std::to_string(size) + "@" + std::to_string(time.time_since_epoch().count());
}

}  // namespace

std::shared_ptr<LoadedCheckpoint> ModelCache::get(const std::string& checkpoint) {
  std::lock_guard<std::mutex> load_lock(load_mutex_);
  const std::string stamp = file_stamp(checkpoint);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = models_.find(checkpoint);
    if (it != models_.end() && it->second.stamp == stamp) return it->second.model;
  }
  std::shared_ptr<LoadedCheckpoint> model = services_.load(checkpoint);
  std::lock_guard<std::mutex> lock(mutex_);
  ++loads_;
  models_[checkpoint] = {stamp, model};
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
