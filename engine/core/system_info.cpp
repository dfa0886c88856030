// System context read from the running process: dladdr on sgemm_, OpenMP, the CPU affinity.
#include "engine/core/system_info.h"

#include <dlfcn.h>
#include <omp.h>

#include <climits>
#include <cstdlib>

#include "engine/core/allocator.h"
#include "engine/core/threads.h"

namespace dynscope {
namespace {

std::string real_path(const std::string& path) {
  char buffer[PATH_MAX];
  return realpath(path.c_str(), buffer) ? std::string(buffer) : path;
}

}  // namespace

BlasInfo blas_info() {
  BlasInfo info;
  void* sgemm = dlsym(RTLD_DEFAULT, "sgemm_");
  Dl_info where{};
  if (sgemm == nullptr || dladdr(sgemm, &where) == 0 || where.dli_fname == nullptr) return info;
  info.library = real_path(where.dli_fname);
  // Debian installs netlib's reference implementation as …/blas/libblas.so.3.
  info.reference = info.library.find("/blas/libblas.so") != std::string::npos;
  using ConfigFn = char* (*)();
  using ThreadsFn = int (*)();
  if (auto config = reinterpret_cast<ConfigFn>(dlsym(RTLD_DEFAULT, "openblas_get_config"))) {
    info.config = config();
  }
  if (auto threads = reinterpret_cast<ThreadsFn>(dlsym(RTLD_DEFAULT, "openblas_get_num_threads"))) {
    info.threads = threads();
  }
  return info;
}

std::vector<std::pair<std::string, std::string>> system_context() {
  std::vector<std::pair<std::string, std::string>> out;
  out.emplace_back("cores", std::to_string(available_cores()));
  out.emplace_back("compute_threads", std::to_string(compute_threads()));
  out.emplace_back("openmp_threads", std::to_string(omp_get_max_threads()));
  out.emplace_back("allocator", allocator_settings());
  const BlasInfo blas = blas_info();
  out.emplace_back("blas", blas.library.empty() ? "none mapped" : blas.library);
  if (!blas.config.empty()) out.emplace_back("blas_config", blas.config);
  if (blas.threads > 0) out.emplace_back("blas_threads", std::to_string(blas.threads));
  if (blas.reference) {
    out.emplace_back("warning",
                     "the reference BLAS is mapped: matrix products run ~5-10x slower; install "
                     "libopenblas0-openmp (Debian) so libblas.so.3 selects OpenBLAS");
  }
  return out;
}

}  // namespace dynscope
