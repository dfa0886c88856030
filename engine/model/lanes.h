// Vector helpers of the fused kernels' arranged paths (point_conv_mlp.cpp): 16- and 8-float
// vectors that every instruction-set clone compiles from the same source, their loads, stores,
// ReLU and lane sums, and the small linears applied to a kernel's aggregate rows. Internal to the
// kernels, like fused_kernels.h.
#pragma once

#include <cstdint>
#include <cstring>

#include "engine/model/fused_kernels.h"

namespace dynscope::fused_detail {

// Vectors of 16 and 8 floats: one AVX-512 or AVX register in the v4 clone, two or more in the
// others (GCC vector extensions, so every clone compiles the same source).
typedef float Lanes16 __attribute__((vector_size(64)));
typedef float Lanes8 __attribute__((vector_size(32)));

// Vectors travel by reference: passed or returned by value they would change the ABI between the
// clones.
template <class V>
DYNSCOPE_KERNEL_BODY void load_lanes(V& v, const float* p) {
  std::memcpy(&v, p, sizeof v);
}

template <class V>
DYNSCOPE_KERNEL_BODY void store_lanes(float* p, const V& v) {
  std::memcpy(p, &v, sizeof v);
}

template <class V>
DYNSCOPE_KERNEL_BODY void relu_lanes(V& v) {
  v = v > 0.0f ? v : V{};
}

// Floats per vector.
template <class V>
constexpr int64_t kLanes = static_cast<int64_t>(sizeof(V) / sizeof(float));

// The sum of a vector's lanes, by halves.
DYNSCOPE_KERNEL_BODY float lane_sum(const Lanes8& v) {
  typedef float Lanes4 __attribute__((vector_size(16)));
  Lanes4 a, b;
  std::memcpy(&a, &v, sizeof a);
  std::memcpy(&b, reinterpret_cast<const char*>(&v) + sizeof a, sizeof b);
  const Lanes4 s4 = a + b;
  return (s4[0] + s4[1]) + (s4[2] + s4[3]);
}

DYNSCOPE_KERNEL_BODY float lane_sum(const Lanes16& v) {
  Lanes8 lo, hi;
  std::memcpy(&lo, &v, sizeof lo);
  std::memcpy(&hi, reinterpret_cast<const char*>(&v) + sizeof lo, sizeof hi);
  return lane_sum(lo + hi);
}

// y[o] = Σ_i w[o·n + i] · x[i] for o < n_out (a linear's weight `[n_out][n]` as LibTorch stores
// it): four outputs at a time, each a vector of partial sums over 16 inputs at a time, summed
// across its lanes at the end.
DYNSCOPE_KERNEL_BODY void apply_linear(float* __restrict y, const float* __restrict x, int64_t n,
                                       const float* __restrict w, int64_t n_out) {
  const int64_t n16 = n / 16 * 16;
  int64_t o = 0;
  for (; o + 4 <= n_out; o += 4) {
    Lanes16 s[4] = {};
    for (int64_t i = 0; i < n16; i += 16) {
      Lanes16 xv;
      load_lanes(xv, x + i);
#pragma GCC unroll 4
      for (int u = 0; u < 4; ++u) {
        Lanes16 wv;
        load_lanes(wv, w + (o + u) * n + i);
        s[u] += xv * wv;
      }
    }
    for (int u = 0; u < 4; ++u) {
      float sum = lane_sum(s[u]);
      for (int64_t i = n16; i < n; ++i) sum += w[(o + u) * n + i] * x[i];
      y[o + u] = sum;
    }
  }
  for (; o < n_out; ++o) {
    Lanes16 s = {};
    for (int64_t i = 0; i < n16; i += 16) {
      Lanes16 xv, wv;
      load_lanes(xv, x + i);
      load_lanes(wv, w + o * n + i);
      s += xv * wv;
    }
    float sum = lane_sum(s);
    for (int64_t i = n16; i < n; ++i) sum += w[o * n + i] * x[i];
    y[o] = sum;
  }
}

// apply_linear for four queries at once: x holds their rows (`[4][n]`), y gets `[4][n_out]`. Each
// weight vector loaded serves the four rows, so the products run at the vector units' rate rather
// than the loads'. kOut outputs at a time, each a V of partial sums per row: 4 × 4 Lanes16 (16
// registers of AVX-512's 32) or, where registers are 16 (AVX2, SSE2), 4 × 2 Lanes8, which keeps
// the sums in registers instead of spilling them at every product.
template <class V = Lanes16, int kOut = 4>
DYNSCOPE_KERNEL_BODY void apply_linear4(float* __restrict y, const float* __restrict x, int64_t n,
                                        const float* __restrict w, int64_t n_out) {
  constexpr int64_t kL = kLanes<V>;
  const int64_t nl = n / kL * kL;
  int64_t o = 0;
  for (; o + kOut <= n_out; o += kOut) {
    V s[4][kOut] = {};  // [query][output]
    for (int64_t i = 0; i < nl; i += kL) {
      V xv[4];
#pragma GCC unroll 4
      for (int r = 0; r < 4; ++r) load_lanes(xv[r], x + r * n + i);
#pragma GCC unroll 4
      for (int u = 0; u < kOut; ++u) {
        V wv;
        load_lanes(wv, w + (o + u) * n + i);
#pragma GCC unroll 4
        for (int r = 0; r < 4; ++r) s[r][u] += xv[r] * wv;
      }
    }
    for (int r = 0; r < 4; ++r) {
      for (int u = 0; u < kOut; ++u) {
        float sum = lane_sum(s[r][u]);
        for (int64_t i = nl; i < n; ++i) sum += w[(o + u) * n + i] * x[r * n + i];
        y[r * n_out + o + u] = sum;
      }
    }
  }
  for (int r = 0; r < 4; ++r) {
    if (o < n_out) apply_linear(y + r * n_out + o, x + r * n, n, w + o * n, n_out - o);
  }
}

// Vector values of a small array in memory, read back one float at a time: the compiler must load
// them from memory (a broadcast load per use) instead of extracting each lane from the register,
// which costs a shuffle or two per lane.
template <class V>
DYNSCOPE_KERNEL_BODY void spill_lanes(float* to, const V& v) {
  store_lanes(to, v);
  asm("" : : "r"(to) : "memory");
}

}  // namespace dynscope::fused_detail
