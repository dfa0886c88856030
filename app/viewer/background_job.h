// BackgroundJob: model work (rollouts, traces) on its own thread, with the ticket of the state it
// was started for and a cancel flag, while the viewer keeps drawing.
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

#include "engine/core/error.h"
#include "engine/core/progress.h"

namespace dynscope::app::viewer {

/// Which state a job was started for (MuJoCo `simulate`'s pending request): the viewer state's
/// generation and checkpoint at the start. A result whose ticket is not current is dropped.
struct JobTicket {
  uint64_t generation = 0;
  std::string checkpoint;
  bool operator==(const JobTicket& o) const {
    return generation == o.generation && checkpoint == o.checkpoint;
  }
  bool operator!=(const JobTicket& o) const { return !(*this == o); }
};

/// Thrown by work that noticed its job was cancelled; the job's result is then dropped.
class JobCancelled : public Error {
 public:
  JobCancelled() : Error("job cancelled") {}
};

/// What running work sees of its job: progress to advance and the cancel flag to poll.
class JobControl {
 public:
  JobControl(Progress* progress, const std::atomic<bool>* cancelled)
      : progress_(progress), cancelled_(cancelled) {}
  /// Progress of the job (never null inside a BackgroundJob).
  Progress* progress() const { return progress_; }
  /// True once the job was cancelled; work should stop at its next step.
  bool cancelled() const { return cancelled_ && cancelled_->load(std::memory_order_acquire); }
  /// Throws JobCancelled when cancelled().
  void check() const {
    if (cancelled()) throw JobCancelled();
  }

 private:
  Progress* progress_;
  const std::atomic<bool>* cancelled_;
};

/// Runs `work` once on a std::thread with a silent Progress of `total` units that the UI reads
/// every frame. The result (or the exception `work` threw) is taken once the job is done. The
/// destructor cancels and waits for the thread, so `work` must own (copy) what it reads.
template <typename T>
class BackgroundJob {
 public:
  /// Starts the thread at once; `label` names the job in the UI, `ticket` the state it serves.
  BackgroundJob(std::string label, JobTicket ticket, int64_t total,
                std::function<T(JobControl&)> work)
      : label_(std::move(label)),
        ticket_(std::move(ticket)),
        progress_(std::make_unique<Progress>(label_, total, Progress::Style::kSilent)) {
    thread_ = std::thread([this, work = std::move(work)] {
      try {
        JobControl control(progress_.get(), &cancelled_);
        result_ = work(control);
      } catch (...) {
        error_ = std::current_exception();
      }
      done_.store(true, std::memory_order_release);
    });
  }
  ~BackgroundJob() {
    cancel();
    if (thread_.joinable()) thread_.join();
  }
  BackgroundJob(const BackgroundJob&) = delete;
  BackgroundJob& operator=(const BackgroundJob&) = delete;

  const std::string& label() const { return label_; }
  const JobTicket& ticket() const { return ticket_; }
  /// Asks the work to stop (it polls JobControl); the result will be dropped.
  void cancel() { cancelled_.store(true, std::memory_order_release); }
  bool cancelled() const { return cancelled_.load(std::memory_order_acquire); }
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
  JobTicket ticket_;
  std::unique_ptr<Progress> progress_;
  std::optional<T> result_;
  std::exception_ptr error_;
  std::atomic<bool> cancelled_{false};
  std::atomic<bool> done_{false};
  std::thread thread_;
};

}  // namespace dynscope::app::viewer
