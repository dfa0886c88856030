// LibTorch context lines and the one place that sets LibTorch's thread count.
#include "engine/model/torch_runtime.h"

#include <ATen/Context.h>
#include <ATen/Parallel.h>
#include <torch/cuda.h>
#include <torch/version.h>

#include "engine/core/system_info.h"
#include "engine/core/threads.h"
#include "engine/model/conv_implementation.h"

namespace dynscope {

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
  return out;
}

void set_torch_threads(int threads) {
  set_compute_threads(threads);
  at::set_num_threads(compute_threads());
}

}  // namespace dynscope
