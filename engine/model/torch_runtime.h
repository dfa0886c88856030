// LibTorch's side of the process context: version, CUDA, intra- and inter-op threads.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace dynscope {

/// system_context() followed by the LibTorch version, whether it was built with CUDA and sees a
/// device, and its intra-op and inter-op thread counts.
std::vector<std::pair<std::string, std::string>> torch_context();

/// Sets the compute-thread budget (engine/core/threads.h) and LibTorch's intra-op threads to
/// `threads` (0: kDefaultComputeThreads). Throws ValueError for a count out of range.
void set_torch_threads(int threads);

}  // namespace dynscope
