// One process-wide budget of compute threads, shared by LibTorch, BLAS and our own parallel loops.
#pragma once

namespace dynscope {

/// Threads our own parallel loops (neighbour search, hierarchy building, pose fitting) may use;
/// always >= 1. The same number is given to OpenMP, which LibTorch's intra-op pool and the
/// OpenMP build of OpenBLAS share, so the process never runs more compute threads than this.
int compute_threads();

/// Sets the budget to `threads` (>= 1), or to kDefaultComputeThreads for 0. Throws ValueError
/// for a negative count or one above kMaxComputeThreads.
void set_compute_threads(int threads);

/// The cores this process may run on (its CPU affinity).
int available_cores();

/// The budget when nothing was set. One thread: at the sizes this project trains and rolls out,
/// a second OpenMP thread gains little on a quiet machine and collapses (spin-waiting at every
/// barrier) when another process keeps a core busy; a training run's prefetch thread or the
/// viewer's UI thread then uses the second core. Ask for more with set_compute_threads.
constexpr int kDefaultComputeThreads = 1;

/// Upper bound of set_compute_threads (a larger count is a typing error, not a machine).
constexpr int kMaxComputeThreads = 1024;

/// CPU time the calling thread has used, in milliseconds (CLOCK_THREAD_CPUTIME_ID): what a
/// frame or a step costs its own thread, independent of other processes and worker threads.
double thread_cpu_ms();

}  // namespace dynscope
