// What this process runs on: the BLAS library serving it, thread counts, cores (no torch, no GL).
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace dynscope {

/// The BLAS serving this process, read from its own mappings (not from the package system).
struct BlasInfo {
  std::string library;      ///< Real path of the library whose sgemm_ the process calls ("" if
                            ///< no BLAS is mapped).
  std::string config;       ///< openblas_get_config() when it is OpenBLAS, else "".
  int threads = 0;          ///< openblas_get_num_threads() when it is OpenBLAS, else 0.
  bool reference = false;   ///< True for Debian's netlib reference BLAS (…/blas/libblas.so.*).
};

/// Looks up sgemm_ in the process and names the mapped file that defines it.
BlasInfo blas_info();

/// Key/value lines describing the machine and this process's compute setup (cores, compute
/// threads, OpenMP threads, heap settings, BLAS library and threads, a warning line for the
/// reference BLAS).
std::vector<std::pair<std::string, std::string>> system_context();

}  // namespace dynscope
