// One process-wide budget of compute threads, shared by LibTorch, BLAS and our own parallel loops.
#pragma once

namespace dynscope {

/// Threads our own parallel loops (neighbour search, hierarchy building, pose fitting) may use;
/// always >= 1. The same number is given to OpenMP, which LibTorch's intra-op pool and the
/// OpenMP build of OpenBLAS share, so the process never runs more compute threads than this.
int compute_threads();

/// Sets the budget to `threads` (>= 1), or to default_compute_threads() for 0. Throws ValueError
/// for a negative count or one above kMaxComputeThreads.
void set_compute_threads(int threads);

/// The budget used when nothing was set: the cores this process may run on.
int default_compute_threads();

/// Upper bound of set_compute_threads (a larger count is a typing error, not a machine).
constexpr int kMaxComputeThreads = 1024;

}  // namespace dynscope
