// Internal helpers of the fused neighbour-convolution kernels (fused_point_conv.cpp and
// point_conv_mlp.cpp): work partitions, compile-time filter widths, the shared inner loops and
// the instruction-set cloning of kernel entry points. Not part of the engine's interface.
#pragma once

#include <torch/autograd.h>
#include <torch/types.h>

#include <algorithm>
#include <string>

#include "engine/core/error.h"
#include "engine/core/isa_clones.h"
#include "engine/core/threads.h"
#include "engine/model/conv_implementation.h"

namespace dynscope::fused_detail {

using torch::autograd::AutogradContext;
using torch::autograd::tensor_list;

// Query rows per parallel task: large enough that scheduling costs nothing next to the work.
constexpr int64_t kGrain = 64;

// Every kernel body below is force-inlined into two entry points: one compiled for the baseline
// instruction set (ConvImplementation::kFusedBaseline) and one with DYNSCOPE_ISA_CLONES
// (engine/core/isa_clones.h: cloned for the x86-64 levels v4 and v3 and the baseline). The inner
// loops run over the filter width J, which `omp simd` vectorises to J lanes.
// fused_kernel_isa() reports the clone by the same dispatch on the same two targets.
#define DYNSCOPE_KERNEL_BODY __attribute__((always_inline)) inline

inline bool use_simd_clones() {
  return conv_implementation() != ConvImplementation::kFusedBaseline;
}

inline std::string shape(const torch::Tensor& t) {
  if (!t.defined()) return "undefined";
  std::string s = "[";
  for (int64_t d = 0; d < t.dim(); ++d) s += (d ? "," : "") + std::to_string(t.size(d));
  return s + "]";
}

inline void check_index(const torch::Tensor& index, int64_t m, int64_t k, const char* op) {
  if (index.scalar_type() != torch::kInt64 || index.dim() != 2 || index.size(0) != m ||
      index.size(1) != k) {
    throw ValueError(op, "index must be int64 [" + std::to_string(m) + "," + std::to_string(k) +
                             "], got " + shape(index));
  }
}

inline void check_float(const torch::Tensor& t, torch::ScalarType dtype, const char* what,
                        const char* op) {
  if (t.scalar_type() != dtype || !t.device().is_cpu()) {
    throw ValueError(op, std::string(what) + " must be a CPU tensor of the features' dtype");
  }
}

// Splits [0, m) into one contiguous range per worker, so each worker can own a scatter buffer.
struct Partition {
  int64_t parts;
  int64_t rows;
  int64_t begin(int64_t p) const { return std::min(rows, p * ((rows + parts - 1) / parts)); }
  int64_t end(int64_t p) const { return begin(p + 1); }
};

inline Partition partition(int64_t rows) {
  const int64_t threads = std::max<int64_t>(1, compute_threads());
  return {std::max<int64_t>(1, std::min(threads, (rows + kGrain - 1) / kGrain)), rows};
}

// The inner loops run over the filter width J (c_mid); with J known at compile time (the default
// 16, and 8) they become a few full vector operations. kJ = 0 reads J at run time.
template <int kJ>
struct Width {
  int64_t j;
  constexpr int64_t operator()() const { return kJ > 0 ? kJ : j; }
};

// acc[c·J + j] += x[c] · h[j] for c < n: the outer product of one neighbour, transposed so the
// contiguous inner loop runs over J.
template <typename T, int kJ>
DYNSCOPE_KERNEL_BODY void add_outer(T* __restrict acc, const T* __restrict x, int64_t n,
                                    const T* __restrict h, Width<kJ> width) {
  const int64_t jn = width();
  for (int64_t c = 0; c < n; ++c) {
    const T xc = x[c];
    T* __restrict row = acc + c * jn;
#pragma omp simd
    for (int64_t jj = 0; jj < jn; ++jj) row[jj] += xc * h[jj];
  }
}

// dh[j] = Σ_c g[c·J + j] x[c] over the transposed gradient row g, for one neighbour.
template <typename T, int kJ>
DYNSCOPE_KERNEL_BODY void add_filter_grad(T* __restrict dh, const T* __restrict gt,
                                          const T* __restrict x, int64_t n, Width<kJ> width) {
  const int64_t jn = width();
  for (int64_t c = 0; c < n; ++c) {
    const T xc = x[c];
    const T* __restrict row = gt + c * jn;
#pragma omp simd
    for (int64_t jj = 0; jj < jn; ++jj) dh[jj] += xc * row[jj];
  }
}

// Calls `f(Width<...>)` with J fixed at compile time where it is a common width.
template <typename F>
void with_width(int64_t j, F&& f) {
  if (j == 16) return f(Width<16>{16});
  if (j == 8) return f(Width<8>{8});
  f(Width<0>{j});
}

// Checks every entry of an int64 index (check_index passed) lies in [-1, n_src). One plain pass
// over the data: the two LibTorch reductions and their item() calls it replaces cost more than
// the pass itself, for every convolution of every forward.
inline void check_index_range(const torch::Tensor& index, int64_t n_src, const char* op) {
  if (index.numel() == 0) return;
  const torch::Tensor c = index.is_contiguous() ? index : index.contiguous();
  const int64_t* p = c.data_ptr<int64_t>();
  const int64_t n = c.numel();
  int64_t hi = p[0], lo = p[0];
#pragma omp simd reduction(max : hi) reduction(min : lo)
  for (int64_t i = 0; i < n; ++i) {
    hi = p[i] > hi ? p[i] : hi;
    lo = p[i] < lo ? p[i] : lo;
  }
  if (hi >= n_src || lo < -1) {
    throw ValueError(op, "index out of range [-1, " + std::to_string(n_src) + "): holds " +
                             std::to_string(lo) + ".." + std::to_string(hi));
  }
}

}  // namespace dynscope::fused_detail
