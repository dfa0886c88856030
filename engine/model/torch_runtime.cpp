// LibTorch context lines, the one place that sets LibTorch's thread count, and the allocator
// settings of every process that runs the model.
#include "engine/model/torch_runtime.h"

#include <ATen/Context.h>
#include <ATen/Parallel.h>
#include <torch/cuda.h>
#include <torch/version.h>

#include "engine/core/allocator.h"
#include "engine/core/system_info.h"
#include "engine/core/threads.h"
#include "engine/model/conv_implementation.h"

namespace dynscope {
namespace {

// LibTorch's CPU tensors come from malloc, and a model step frees and reallocates the same few
// megabytes every time. With glibc's defaults the freed top of the heap goes back to the kernel
// and the next step faults it in again, zeroed: 11 % of a training step's profile was page
// faults. configure_allocator() keeps freed memory for reuse.
const bool kAllocatorConfigured = [] {
  configure_allocator();
  return true;
}();

}  // namespace

std::vector<std::pair<std::string, std::string>> torch_context() {
  std::vector<std::pair<std::string, std::string>> out = system_context();
  out.emplace_back("libtorch", TORCH_VERSION);
  out.emplace_back("cuda", at::hasCUDA()
                               ? (torch::cuda::is_available()
                                      ? std::to_string(torch::cuda::device_count()) + " device(s)"
                                      : "built with CUDA, no device")
                               : "not built with CUDA");
  out.emplace_back("torch_intraop_threads", std::to_string(at::get_num_threads()));
  out.emplace_back("torch_interop_threads", std::to_string(at::get_num_interop_threads()));
  out.emplace_back("kernel_isa", fused_kernel_isa());
  out.emplace_back("kernel_blocking", fused_kernel_blocking());
  return out;
}

void set_torch_threads(int threads) {
  set_compute_threads(threads);
  at::set_num_threads(compute_threads());
}

}  // namespace dynscope
