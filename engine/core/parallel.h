// The one way our loops run on the compute threads: a parallel loop on its own, or tasks shared
// by the threads of a region opened with on_compute_threads (a hierarchy's lists built side by
// side).
#pragma once

#include <omp.h>

#include <algorithm>
#include <cstdint>
#include <exception>
#include <mutex>

#include "engine/core/threads.h"

namespace dynscope {

/// Calls body(begin, end) for the consecutive chunks [0, chunk), [chunk, 2 chunk), ... of [0, n),
/// in parallel when `parallel` is true and there are compute threads to share. Outside a parallel
/// region it opens one of compute_threads() threads with a dynamic schedule; inside one (see
/// on_compute_threads) it makes the chunks tasks that any thread of the region may run, groups
/// of them so that a task is worth its scheduling, and runs tasks itself until all are done.
/// Either way every chunk has run when it returns. `body` must not throw and must write only
/// what its chunk owns. A chunk that starts no tasks or loops of its own runs on one thread from
/// start to end, with no point where the thread could take up another task, so it may use
/// thread_local scratch.
template <typename Body>
void parallel_chunks(int64_t n, int64_t chunk, bool parallel, const Body& body) {
  if (n <= 0) return;
  const int64_t chunks = (n + chunk - 1) / chunk;
  const auto run = [&](int64_t c) { body(c * chunk, std::min(n, (c + 1) * chunk)); };
  if (parallel && chunks > 1 && omp_in_parallel()) {
    // A task per few chunks: libgomp queues every task under one lock, so thousands of tiny
    // tasks would cost more than they balance.
    const int64_t tasks = std::min<int64_t>(chunks, 4 * omp_get_num_threads());
#pragma omp taskloop num_tasks(tasks) default(shared)
    for (int64_t c = 0; c < chunks; ++c) run(c);
    return;
  }
  const int threads = parallel && chunks > 1 ? compute_threads() : 1;
  if (threads < 2) {
    for (int64_t c = 0; c < chunks; ++c) run(c);
    return;
  }
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1)
  for (int64_t c = 0; c < chunks; ++c) run(c);
}

/// Runs `work` on the calling thread inside one parallel region of compute_threads() threads,
/// the others waiting for tasks: the parallel_chunks loops and the tasks (`#pragma omp task`)
/// `work` starts are then shared by all of them, so that independent pieces of work run side by
/// side instead of one loop after the other. Without a second thread, or inside a region already,
/// it just calls `work`. `work` must wait for its tasks (`#pragma omp taskwait`) before it
/// returns. An exception from `work` is rethrown here.
template <typename Work>
void on_compute_threads(const Work& work) {
  const int threads = omp_in_parallel() ? 1 : compute_threads();
  if (threads < 2) {
    work();
    return;
  }
  std::exception_ptr failed;
  // `master`, not `single`: `work` runs on the calling thread, with its thread-local state
  // (LibTorch's grad mode among it); the other threads take tasks at the region's closing barrier.
#pragma omp parallel num_threads(threads)
#pragma omp master
  {
    try {
      work();
    } catch (...) {
      failed = std::current_exception();
    }
  }
  if (failed) std::rethrow_exception(failed);
}

/// The first exception of several tasks, kept to be rethrown once they have all finished
/// (an exception must not leave an OpenMP task).
class TaskErrors {
 public:
  /// Calls f(), keeping what it throws.
  template <typename F>
  void run(const F& f) noexcept {
    try {
      f();
    } catch (...) {
      const std::lock_guard<std::mutex> lock(mutex_);
      if (!first_) first_ = std::current_exception();
    }
  }
  /// Rethrows the first exception kept, if any.
  void rethrow() const {
    if (first_) std::rethrow_exception(first_);
  }

 private:
  std::mutex mutex_;
  std::exception_ptr first_;
};

}  // namespace dynscope
