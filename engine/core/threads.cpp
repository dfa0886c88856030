// Compute-thread budget: one atomic count mirrored into OpenMP.
#include "engine/core/threads.h"

#include <omp.h>
#include <sched.h>
#include <time.h>

#include <algorithm>
#include <atomic>
#include <string>
#include <thread>

#include "engine/core/error.h"

namespace dynscope {
namespace {

std::atomic<int> g_threads{0};  // 0: not set yet

}  // namespace

int available_cores() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) == 0) return std::max(1, CPU_COUNT(&set));
  return std::max(1u, std::thread::hardware_concurrency());
}

int compute_threads() {
  const int n = g_threads.load(std::memory_order_relaxed);
  return n > 0 ? n : kDefaultComputeThreads;
}

void set_compute_threads(int threads) {
  if (threads < 0 || threads > kMaxComputeThreads) {
    throw ValueError("threads", "must be in [0, " + std::to_string(kMaxComputeThreads) +
                                    "] (0: the default, 1), got " + std::to_string(threads));
  }
  const int n = threads == 0 ? kDefaultComputeThreads : threads;
  g_threads.store(n, std::memory_order_relaxed);
  omp_set_num_threads(n);
}

double thread_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
}

}  // namespace dynscope
