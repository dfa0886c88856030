// BackgroundJob: model work (rollouts, traces) on its own thread while the viewer keeps drawing.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <exception>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <utility>

#include "engine/core/progress.h"

namespace dynscope::app::viewer {

/// Runs `work` once on a std::thread with a silent Progress of `total` units that the UI reads
/// every frame. The result (or the exception `work` threw) is taken once the job is done. The
/// destructor waits for the thread, so a job must not outlive what `work` references.
template <typename T>
class BackgroundJob {
 public:
  /// Starts the thread at once; `label` names the job in the UI.
  BackgroundJob(std::string label, int64_t total, std::function<T(Progress*)> work)
      : label_(std::move(label)),
        progress_(std::make_unique<Progress>(label_, total, Progress::Style::kSilent)) {
    thread_ = std::thread([this, work = std::move(work)] {
      try {
        result_ = work(progress_.get());
      } catch (...) {
        error_ = std::current_exception();
      }
      done_.store(true, std::memory_order_release);
    });
  }
  ~BackgroundJob() {
    if (thread_.joinable()) thread_.join();
  }
  BackgroundJob(const BackgroundJob&) = delete;
  BackgroundJob& operator=(const BackgroundJob&) = delete;

  const std::string& label() const { return label_; }
  /// True once `work` has returned or thrown.
  bool done() const { return done_.load(std::memory_order_acquire); }
  /// Share of the units done, in [0, 1] (0 while the total is unknown).
  float fraction() const {
    const int64_t total = progress_->total();
    return total > 0 ? std::min(1.0f, static_cast<float>(progress_->done()) / total) : 0.0f;
  }
  /// The result once done(): joins the thread and rethrows what `work` threw.
  T take() {
    if (thread_.joinable()) thread_.join();
    if (error_) std::rethrow_exception(error_);
    return std::move(*result_);
  }

 private:
  std::string label_;
  std::unique_ptr<Progress> progress_;
  std::optional<T> result_;
  std::exception_ptr error_;
  std::atomic<bool> done_{false};
  std::thread thread_;
};

}  // namespace dynscope::app::viewer
