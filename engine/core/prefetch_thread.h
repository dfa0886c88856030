// One job at a time on a thread of its own, its result taken later: work prepared ahead.
#pragma once

#include <condition_variable>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <utility>

namespace dynscope {

/// Runs one job at a time on its own thread while the caller goes on: start() hands it a job,
/// take() waits for the result (rethrowing what the job threw). The thread lives as long as the
/// object; destruction waits for a running job to finish and discards its result.
template <typename T>
class PrefetchThread {
 public:
  PrefetchThread() : thread_([this] { loop(); }) {}
  ~PrefetchThread() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    thread_.join();
  }
  PrefetchThread(const PrefetchThread&) = delete;
  PrefetchThread& operator=(const PrefetchThread&) = delete;

  /// Starts `job`; the previous job's result must have been taken.
  void start(std::function<T()> job) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      job_ = std::move(job);
      ready_ = false;
    }
    wake_.notify_all();
  }

  /// Waits for the started job and returns its result; rethrows what it threw.
  T take() {
    std::unique_lock<std::mutex> lock(mutex_);
    wake_.wait(lock, [this] { return ready_; });
    ready_ = false;
    if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
    return std::move(result_);
  }

 private:
  void loop() {
    std::unique_lock<std::mutex> lock(mutex_);
    while (true) {
      wake_.wait(lock, [this] { return stop_ || job_; });
      if (stop_) return;
      std::function<T()> job = std::move(job_);
      job_ = nullptr;
      lock.unlock();
      T result{};
      std::exception_ptr error;
      try {
        result = job();
      } catch (...) {
        error = std::current_exception();
      }
      lock.lock();
      result_ = std::move(result);
      error_ = error;
      ready_ = true;
      wake_.notify_all();
    }
  }

  std::mutex mutex_;
  std::condition_variable wake_;
  std::function<T()> job_;
  T result_{};
  std::exception_ptr error_;
  bool ready_ = false, stop_ = false;
  std::thread thread_;  // last: started once the members it reads exist
};

}  // namespace dynscope
