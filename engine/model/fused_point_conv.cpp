// Fused PointConv aggregation and message gather: CPU kernels parallel over query points, with
// hand-written backward passes (LibTorch's bmm on M tiny matrices dispatches one matrix at a time).
#include "engine/model/fused_point_conv.h"

#include <ATen/Dispatch.h>
#include <ATen/Parallel.h>
#include <torch/autograd.h>

#include <atomic>
#include <string>
#include <vector>

#include "engine/core/error.h"
#include "engine/model/conv_implementation.h"

namespace dynscope {
namespace {

using torch::autograd::AutogradContext;
using torch::autograd::tensor_list;

// Query rows per parallel task: large enough that scheduling costs nothing next to the work.
constexpr int64_t kGrain = 64;

// Every kernel body below is force-inlined into two entry points: one compiled for the baseline
// instruction set (ConvImplementation::kFusedBaseline) and one cloned for AVX-512, AVX2+FMA and the
// baseline, the clone chosen once at load time from the CPU (GCC function multiversioning). The
// inner loops run over the filter width J, which `omp simd` vectorises to J lanes.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define DYNSCOPE_SIMD_CLONES \
  __attribute__((target_clones("arch=skylake-avx512", "arch=haswell", "default")))
#else
#define DYNSCOPE_SIMD_CLONES
#endif
#define DYNSCOPE_KERNEL_BODY __attribute__((always_inline)) inline

bool use_simd_clones() { return conv_implementation() != ConvImplementation::kFusedBaseline; }

std::string shape(const torch::Tensor& t) {
  if (!t.defined()) return "undefined";
  std::string s = "[";
  for (int64_t d = 0; d < t.dim(); ++d) s += (d ? "," : "") + std::to_string(t.size(d));
  return s + "]";
}

void check_index(const torch::Tensor& index, int64_t m, int64_t k, const char* op) {
  if (index.scalar_type() != torch::kInt64 || index.dim() != 2 || index.size(0) != m ||
      index.size(1) != k) {
    throw ValueError(op, "index must be int64 [" + std::to_string(m) + "," + std::to_string(k) +
                             "], got " + shape(index));
  }
}

void check_float(const torch::Tensor& t, torch::ScalarType dtype, const char* what,
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

Partition partition(int64_t rows) {
  const int64_t threads = std::max<int64_t>(1, at::get_num_threads());
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

// Arguments of the aggregation kernels (one struct, so each entry point takes one argument).
template <typename T>
struct AggregateArgs {
  const T* features;
  const T* edge;
  const T* h;
  const int64_t* index;
  int64_t k, c, p;
};

// Rows [begin, end) of out[m, j·C' + c] = Σ_k h[m,k,j] x[m,k,c], x = [features[idx]; edge];
// `acc` holds C'·J scratch values.
template <typename T, int kJ>
DYNSCOPE_KERNEL_BODY void aggregate_rows_body(const AggregateArgs<T>& a, T* out, int64_t begin,
                                              int64_t end, Width<kJ> width, T* acc) {
  const int64_t ct = a.c + a.p, j = width(), k = a.k;
  for (int64_t q = begin; q < end; ++q) {
    std::fill(acc, acc + ct * j, T(0));
    for (int64_t n = 0; n < k; ++n) {
      const int64_t e = q * k + n;
      const int64_t src = a.index[e];
      if (src < 0) continue;
      const T* hk = a.h + e * j;
      add_outer(acc, a.features + src * a.c, a.c, hk, width);
      add_outer(acc + a.c * j, a.edge + e * a.p, a.p, hk, width);
    }
    T* o = out + q * j * ct;
    for (int64_t jj = 0; jj < j; ++jj) {
      for (int64_t cc = 0; cc < ct; ++cc) o[jj * ct + cc] = acc[cc * j + jj];
    }
  }
}

template <typename T, int kJ>
void aggregate_rows_baseline(const AggregateArgs<T>& a, T* out, int64_t begin, int64_t end,
                             Width<kJ> width, T* acc) {
  aggregate_rows_body(a, out, begin, end, width, acc);
}

template <typename T, int kJ>
DYNSCOPE_SIMD_CLONES void aggregate_rows_simd(const AggregateArgs<T>& a, T* out, int64_t begin,
                                              int64_t end, Width<kJ> width, T* acc) {
  aggregate_rows_body(a, out, begin, end, width, acc);
}

template <typename T, int kJ>
void aggregate_forward(const T* features, const T* edge, const T* h, const int64_t* index, T* out,
                       int64_t m, int64_t k, int64_t c, int64_t p, Width<kJ> width) {
  const AggregateArgs<T> args{features, edge, h, index, k, c, p};
  const bool simd = use_simd_clones();
  at::parallel_for(0, m, kGrain, [&](int64_t begin, int64_t end) {
    std::vector<T> acc(static_cast<size_t>((c + p) * width()));
    if (simd) {
      aggregate_rows_simd(args, out, begin, end, width, acc.data());
    } else {
      aggregate_rows_baseline(args, out, begin, end, width, acc.data());
    }
  });
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

// Gradient outputs of the aggregation for one range of query rows.
template <typename T>
struct AggregateGrads {
  const T* grad;  ///< `[M, J·C']`.
  T* d_feat;      ///< This worker's scatter buffer `[N,C]` or null.
  T* d_edge;      ///< `[M,K,P]` or null.
  T* d_h;         ///< `[M,K,J]` or null.
};

// Gradients of aggregate_forward for rows [begin, end); `gt` (C'·J) and `dx` (C') are scratch.
template <typename T, int kJ>
DYNSCOPE_KERNEL_BODY void aggregate_grad_rows_body(const AggregateArgs<T>& a,
                                                   const AggregateGrads<T>& d, int64_t begin,
                                                   int64_t end, Width<kJ> width, T* gt, T* dx) {
  const int64_t c = a.c, p = a.p, k = a.k, ct = c + p, j = width();
  for (int64_t q = begin; q < end; ++q) {
    const T* g = d.grad + q * j * ct;
    if (d.d_h) {
      for (int64_t jj = 0; jj < j; ++jj) {
        for (int64_t cc = 0; cc < ct; ++cc) gt[cc * j + jj] = g[jj * ct + cc];
      }
    }
    for (int64_t n = 0; n < k; ++n) {
      const int64_t e = q * k + n;
      const int64_t src = a.index[e];
      if (src < 0) {
        if (d.d_h) std::fill(d.d_h + e * j, d.d_h + (e + 1) * j, T(0));
        if (d.d_edge) std::fill(d.d_edge + e * p, d.d_edge + (e + 1) * p, T(0));
        continue;
      }
      const T* hk = a.h + e * j;
      if (d.d_h) {
        T* dh = d.d_h + e * j;
        std::fill(dh, dh + j, T(0));
        add_filter_grad(dh, gt, a.features + src * c, c, width);
        add_filter_grad(dh, gt + c * j, a.edge + e * p, p, width);
      }
      if (d.d_feat || d.d_edge) {
        // dx[c] = Σ_j h[j] g[j·C' + c]: axpy over the contiguous C' per filter channel.
        std::fill(dx, dx + ct, T(0));
        for (int64_t jj = 0; jj < j; ++jj) {
          const T hj = hk[jj];
          const T* __restrict row = g + jj * ct;
#pragma omp simd
          for (int64_t cc = 0; cc < ct; ++cc) dx[cc] += hj * row[cc];
        }
        if (d.d_feat) {
          T* __restrict dst = d.d_feat + src * c;
#pragma omp simd
          for (int64_t cc = 0; cc < c; ++cc) dst[cc] += dx[cc];
        }
        if (d.d_edge) std::copy(dx + c, dx + ct, d.d_edge + e * p);
      }
    }
  }
}

template <typename T, int kJ>
void aggregate_grad_rows_baseline(const AggregateArgs<T>& a, const AggregateGrads<T>& d,
                                  int64_t begin, int64_t end, Width<kJ> width, T* gt, T* dx) {
  aggregate_grad_rows_body(a, d, begin, end, width, gt, dx);
}

template <typename T, int kJ>
DYNSCOPE_SIMD_CLONES void aggregate_grad_rows_simd(const AggregateArgs<T>& a,
                                                   const AggregateGrads<T>& d, int64_t begin,
                                                   int64_t end, Width<kJ> width, T* gt, T* dx) {
  aggregate_grad_rows_body(a, d, begin, end, width, gt, dx);
}

// Gradients of aggregate_forward. d_features is scattered into one buffer per worker (`buffers`
// `[parts,N,C]`) so no two threads write the same row; the caller sums them.
template <typename T, int kJ>
void aggregate_backward(const T* features, const T* edge, const T* h, const int64_t* index,
                        const T* grad, T* d_buffers, T* d_edge, T* d_h, int64_t n_src, int64_t m,
                        int64_t k, int64_t c, int64_t p, Width<kJ> width, const Partition& part) {
  const int64_t ct = c + p, j = width();
  const AggregateArgs<T> args{features, edge, h, index, k, c, p};
  const bool simd = use_simd_clones();
  at::parallel_for(0, part.parts, 1, [&](int64_t first, int64_t last) {
    std::vector<T> gt(static_cast<size_t>(ct * j)), dx(static_cast<size_t>(ct));
    for (int64_t w = first; w < last; ++w) {
      const AggregateGrads<T> d{grad, d_buffers ? d_buffers + w * n_src * c : nullptr, d_edge, d_h};
      if (simd) {
        aggregate_grad_rows_simd(args, d, part.begin(w), part.end(w), width, gt.data(), dx.data());
      } else {
        aggregate_grad_rows_baseline(args, d, part.begin(w), part.end(w), width, gt.data(),
                                     dx.data());
      }
    }
  });
}

// Calls `f(Width<...>)` with J fixed at compile time where it is a common width.
template <typename F>
void with_width(int64_t j, F&& f) {
  if (j == 16) return f(Width<16>{16});
  if (j == 8) return f(Width<8>{8});
  f(Width<0>{j});
}

struct AggregateFunction : torch::autograd::Function<AggregateFunction> {
  static torch::Tensor forward(AutogradContext* ctx, torch::Tensor features, torch::Tensor edge,
                               torch::Tensor h, torch::Tensor index) {
    features = features.contiguous();
    edge = edge.contiguous();
    h = h.contiguous();
    index = index.contiguous();
    const int64_t m = h.size(0), k = h.size(1), j = h.size(2);
    const int64_t c = features.size(1), p = edge.size(2);
    torch::Tensor out = torch::empty({m, j * (c + p)}, features.options());
    AT_DISPATCH_FLOATING_TYPES(features.scalar_type(), "point_conv_aggregate", [&] {
      with_width(j, [&](auto width) {
        aggregate_forward<scalar_t>(features.data_ptr<scalar_t>(), edge.data_ptr<scalar_t>(),
                                    h.data_ptr<scalar_t>(), index.data_ptr<int64_t>(),
                                    out.data_ptr<scalar_t>(), m, k, c, p, width);
      });
    });
    ctx->save_for_backward({features, edge, h, index});
    return out;
  }

  static tensor_list backward(AutogradContext* ctx, tensor_list grads) {
    const auto saved = ctx->get_saved_variables();
    const torch::Tensor &features = saved[0], &edge = saved[1], &h = saved[2], &index = saved[3];
    const torch::Tensor grad = grads[0].contiguous();
    const int64_t m = h.size(0), k = h.size(1), j = h.size(2);
    const int64_t n_src = features.size(0), c = features.size(1), p = edge.size(2);
    const bool want_feat = ctx->needs_input_grad(0), want_edge = ctx->needs_input_grad(1),
               want_h = ctx->needs_input_grad(2);
    const Partition part = partition(m);
    torch::Tensor buffers, d_edge, d_h;
    if (want_feat) buffers = torch::zeros({part.parts, n_src, c}, features.options());
    if (want_edge) d_edge = torch::empty_like(edge);
    if (want_h) d_h = torch::empty_like(h);
    AT_DISPATCH_FLOATING_TYPES(features.scalar_type(), "point_conv_aggregate_backward", [&] {
      auto ptr = [](torch::Tensor& t) { return t.defined() ? t.data_ptr<scalar_t>() : nullptr; };
      with_width(j, [&](auto width) {
        aggregate_backward<scalar_t>(features.data_ptr<scalar_t>(), edge.data_ptr<scalar_t>(),
                                     h.data_ptr<scalar_t>(), index.data_ptr<int64_t>(),
                                     grad.data_ptr<scalar_t>(), ptr(buffers), ptr(d_edge), ptr(d_h),
                                     n_src, m, k, c, p, width, part);
      });
    });
    torch::Tensor d_features;
    if (want_feat) d_features = part.parts == 1 ? buffers[0] : buffers.sum(0);
    return {d_features, d_edge, d_h, torch::Tensor()};
  }
};

// The inference aggregation's weights, transposed so every inner loop runs over outputs.
struct InferenceArgs {
  const float* features;
  const float* rel;
  const float* gate;  // null: 1
  const int64_t* index;
  int64_t k, c, p, hidden, pos_hidden;
  const float *w1, *b1, *w2t, *b2, *w3t, *b3;  // w1 [H,3]; w2t [H,H] (in, out); w3t [H,J]
  const float *e1, *c1, *e2t, *c2;             // e1 [P,3]; e2t [P,P] (in, out); null: none
};

// y[o] = bias[o] + Σ_i x[i] wt[i·n + o] for o < n, then ReLU when `relu`.
DYNSCOPE_KERNEL_BODY void small_linear(float* __restrict y, const float* __restrict x, int64_t in,
                                       const float* __restrict wt, const float* __restrict bias,
                                       int64_t n, bool relu) {
  std::copy(bias, bias + n, y);
  for (int64_t i = 0; i < in; ++i) {
    const float xi = x[i];
    const float* __restrict row = wt + i * n;
#pragma omp simd
    for (int64_t o = 0; o < n; ++o) y[o] += xi * row[o];
  }
  if (relu) {
#pragma omp simd
    for (int64_t o = 0; o < n; ++o) y[o] = y[o] > 0.0f ? y[o] : 0.0f;
  }
}

// First layer from a 3-vector: y[o] = relu(bias[o] + w[o,:]·r).
DYNSCOPE_KERNEL_BODY void first_layer(float* __restrict y, const float* __restrict r,
                                      const float* __restrict w, const float* __restrict bias,
                                      int64_t n) {
  for (int64_t o = 0; o < n; ++o) {
    const float v = bias[o] + w[3 * o] * r[0] + w[3 * o + 1] * r[1] + w[3 * o + 2] * r[2];
    y[o] = v > 0.0f ? v : 0.0f;
  }
}

// Rows [begin, end) of the inference aggregation; `scratch` holds C'·J + 2·H + J + 2·P floats.
template <int kJ>
DYNSCOPE_KERNEL_BODY void inference_rows_body(const InferenceArgs& a, float* out, int64_t begin,
                                              int64_t end, Width<kJ> width, float* scratch) {
  const int64_t j = width(), c = a.c, p = a.p, ct = c + p, k = a.k;
  float* acc = scratch;
  float* h1 = acc + ct * j;
  float* h2 = h1 + a.hidden;
  float* hk = h2 + a.hidden;
  float* p1 = hk + j;
  float* pe = p1 + a.pos_hidden;
  for (int64_t q = begin; q < end; ++q) {
    std::fill(acc, acc + ct * j, 0.0f);
    for (int64_t n = 0; n < k; ++n) {
      const int64_t e = q * k + n;
      const int64_t src = a.index[e];
      if (src < 0) continue;
      const float* r = a.rel + e * 3;
      first_layer(h1, r, a.w1, a.b1, a.hidden);
      small_linear(h2, h1, a.hidden, a.w2t, a.b2, a.hidden, true);
      small_linear(hk, h2, a.hidden, a.w3t, a.b3, j, false);
      if (a.gate) {
        const float g = a.gate[e];
#pragma omp simd
        for (int64_t jj = 0; jj < j; ++jj) hk[jj] *= g;
      }
      add_outer(acc, a.features + src * c, c, hk, width);
      if (p > 0) {
        first_layer(p1, r, a.e1, a.c1, a.pos_hidden);
        small_linear(pe, p1, a.pos_hidden, a.e2t, a.c2, p, false);
        add_outer(acc + c * j, pe, p, hk, width);
      }
    }
    float* o = out + q * j * ct;
    for (int64_t jj = 0; jj < j; ++jj) {
      for (int64_t cc = 0; cc < ct; ++cc) o[jj * ct + cc] = acc[cc * j + jj];
    }
  }
}

template <int kJ>
void inference_rows_baseline(const InferenceArgs& a, float* out, int64_t begin, int64_t end,
                             Width<kJ> width, float* scratch) {
  inference_rows_body(a, out, begin, end, width, scratch);
}

template <int kJ>
DYNSCOPE_SIMD_CLONES void inference_rows_simd(const InferenceArgs& a, float* out, int64_t begin,
                                              int64_t end, Width<kJ> width, float* scratch) {
  inference_rows_body(a, out, begin, end, width, scratch);
}

// Rows [begin, end) of out[m,k] = q[m] + s[idx] + r[m,k] (0 where idx < 0).
template <typename T>
DYNSCOPE_KERNEL_BODY void gather_add_rows_body(const T* q, const T* s, const T* r,
                                               const int64_t* index, T* out, int64_t begin,
                                               int64_t end, int64_t k, int64_t hdim) {
  for (int64_t row = begin; row < end; ++row) {
    const T* __restrict qr = q + row * hdim;
    for (int64_t n = 0; n < k; ++n) {
      const int64_t e = row * k + n;
      T* __restrict o = out + e * hdim;
      const int64_t src = index[e];
      if (src < 0) {
        std::fill(o, o + hdim, T(0));
        continue;
      }
      const T* __restrict sr = s + src * hdim;
      if (r) {
        const T* __restrict rr = r + e * hdim;
#pragma omp simd
        for (int64_t c = 0; c < hdim; ++c) o[c] = qr[c] + sr[c] + rr[c];
      } else {
#pragma omp simd
        for (int64_t c = 0; c < hdim; ++c) o[c] = qr[c] + sr[c];
      }
    }
  }
}

template <typename T>
void gather_add_rows_baseline(const T* q, const T* s, const T* r, const int64_t* index, T* out,
                              int64_t begin, int64_t end, int64_t k, int64_t hdim) {
  gather_add_rows_body(q, s, r, index, out, begin, end, k, hdim);
}

template <typename T>
DYNSCOPE_SIMD_CLONES void gather_add_rows_simd(const T* q, const T* s, const T* r,
                                               const int64_t* index, T* out, int64_t begin,
                                               int64_t end, int64_t k, int64_t hdim) {
  gather_add_rows_body(q, s, r, index, out, begin, end, k, hdim);
}

template <typename T>
void gather_add_forward(const T* q, const T* s, const T* r, const int64_t* index, T* out, int64_t m,
                        int64_t k, int64_t hdim) {
  const bool simd = use_simd_clones();
  at::parallel_for(0, m, kGrain, [&](int64_t begin, int64_t end) {
    if (simd) {
      gather_add_rows_simd(q, s, r, index, out, begin, end, k, hdim);
    } else {
      gather_add_rows_baseline(q, s, r, index, out, begin, end, k, hdim);
    }
  });
}

template <typename T>
void gather_add_backward(const T* grad, const int64_t* index, T* d_q, T* d_buffers, T* d_r,
                         int64_t n_src, int64_t m, int64_t k, int64_t hdim, const Partition& part) {
  at::parallel_for(0, part.parts, 1, [&](int64_t first, int64_t last) {
    for (int64_t w = first; w < last; ++w) {
      T* d_s = d_buffers ? d_buffers + w * n_src * hdim : nullptr;
      for (int64_t row = part.begin(w); row < part.end(w); ++row) {
        if (d_q) std::fill(d_q + row * hdim, d_q + (row + 1) * hdim, T(0));
        for (int64_t n = 0; n < k; ++n) {
          const int64_t e = row * k + n;
          const T* g = grad + e * hdim;
          const int64_t src = index[e];
          if (src < 0) {
            if (d_r) std::fill(d_r + e * hdim, d_r + (e + 1) * hdim, T(0));
            continue;
          }
          if (d_q) {
            for (int64_t c = 0; c < hdim; ++c) d_q[row * hdim + c] += g[c];
          }
          if (d_s) {
            for (int64_t c = 0; c < hdim; ++c) d_s[src * hdim + c] += g[c];
          }
          if (d_r) std::copy(g, g + hdim, d_r + e * hdim);
        }
      }
    }
  });
}

struct GatherAddFunction : torch::autograd::Function<GatherAddFunction> {
  static torch::Tensor forward(AutogradContext* ctx, torch::Tensor q, torch::Tensor s,
                               torch::Tensor r, torch::Tensor index) {
    q = q.contiguous();
    s = s.contiguous();
    index = index.contiguous();
    const bool has_r = r.numel() > 0;
    if (has_r) r = r.contiguous();
    const int64_t m = index.size(0), k = index.size(1), hdim = q.size(1);
    torch::Tensor out = torch::empty({m, k, hdim}, q.options());
    AT_DISPATCH_FLOATING_TYPES(q.scalar_type(), "gather_add", [&] {
      gather_add_forward<scalar_t>(q.data_ptr<scalar_t>(), s.data_ptr<scalar_t>(),
                                   has_r ? r.data_ptr<scalar_t>() : nullptr,
                                   index.data_ptr<int64_t>(), out.data_ptr<scalar_t>(), m, k, hdim);
    });
    ctx->save_for_backward({index});
    ctx->saved_data["n_src"] = s.size(0);
    ctx->saved_data["has_r"] = has_r;
    return out;
  }

  static tensor_list backward(AutogradContext* ctx, tensor_list grads) {
    const torch::Tensor index = ctx->get_saved_variables()[0];
    const int64_t n_src = ctx->saved_data["n_src"].toInt();
    const bool has_r = ctx->saved_data["has_r"].toBool();
    const torch::Tensor grad = grads[0].contiguous();
    const int64_t m = index.size(0), k = index.size(1), hdim = grad.size(2);
    const Partition part = partition(m);
    torch::Tensor d_q, buffers, d_r;
    if (ctx->needs_input_grad(0)) d_q = torch::empty({m, hdim}, grad.options());
    if (ctx->needs_input_grad(1)) buffers = torch::zeros({part.parts, n_src, hdim}, grad.options());
    if (has_r && ctx->needs_input_grad(2)) d_r = torch::empty({m, k, hdim}, grad.options());
    AT_DISPATCH_FLOATING_TYPES(grad.scalar_type(), "gather_add_backward", [&] {
      auto ptr = [](torch::Tensor& t) { return t.defined() ? t.data_ptr<scalar_t>() : nullptr; };
      gather_add_backward<scalar_t>(grad.data_ptr<scalar_t>(), index.data_ptr<int64_t>(), ptr(d_q),
                                    ptr(buffers), ptr(d_r), n_src, m, k, hdim, part);
    });
    torch::Tensor d_s;
    if (buffers.defined()) d_s = part.parts == 1 ? buffers[0] : buffers.sum(0);
    return {d_q, d_s, d_r, torch::Tensor()};
  }
};

void check_index_range(const torch::Tensor& index, int64_t n_src, const char* op) {
  if (index.numel() == 0) return;
  const int64_t hi = index.max().item<int64_t>(), lo = index.min().item<int64_t>();
  if (hi >= n_src || lo < -1) {
    throw ValueError(op, "index out of range [-1, " + std::to_string(n_src) + "): holds " +
                             std::to_string(lo) + ".." + std::to_string(hi));
  }
}

std::atomic<ConvImplementation> g_implementation{ConvImplementation::kFused};

}  // namespace

ConvImplementation conv_implementation() { return g_implementation.load(); }

void set_conv_implementation(ConvImplementation implementation) {
  g_implementation.store(implementation);
}

torch::Tensor masked_index(const NeighborTensors& neighbors) {
  // A prepared list already holds −1 wherever its mask is false.
  if (neighbors.rel.defined()) return neighbors.index;
  return torch::where(neighbors.mask, neighbors.index, torch::full_like(neighbors.index, -1));
}

torch::Tensor point_conv_aggregate(const torch::Tensor& features, const torch::Tensor& edge,
                                   const torch::Tensor& h, const torch::Tensor& index) {
  const char* op = "point_conv_aggregate";
  if (features.dim() != 2 || h.dim() != 3) {
    throw ValueError(
        op, "features must be [N,C] and h [M,K,J], got " + shape(features) + " and " + shape(h));
  }
  const auto dtype = features.scalar_type();
  if (dtype != torch::kFloat && dtype != torch::kDouble) {
    throw ValueError(op, "features must be float32 or float64");
  }
  check_float(features, dtype, "features", op);
  check_float(h, dtype, "h", op);
  const int64_t m = h.size(0), k = h.size(1);
  check_index(index, m, k, op);
  torch::Tensor e = edge;
  if (!e.defined()) {
    e = torch::empty({m, k, 0}, features.options());
  } else if (e.dim() != 3 || e.size(0) != m || e.size(1) != k) {
    throw ValueError(op, "edge must be [" + std::to_string(m) + "," + std::to_string(k) +
                             ",P], got " + shape(e));
  }
  check_float(e, dtype, "edge", op);
  check_index_range(index, features.size(0), op);
  return AggregateFunction::apply(features, e, h, index);
}

torch::Tensor point_conv_aggregate_inference(const torch::Tensor& features,
                                             const torch::Tensor& rel, const EdgeMlps& mlps,
                                             const torch::Tensor& gate,
                                             const torch::Tensor& index) {
  const char* op = "point_conv_aggregate_inference";
  if (features.dim() != 2 || rel.dim() != 3 || rel.size(2) != 3) {
    throw ValueError(op, "features must be [N,C] and rel [M,K,3], got " + shape(features) +
                             " and " + shape(rel));
  }
  check_float(features, torch::kFloat, "features", op);
  check_float(rel, torch::kFloat, "rel", op);
  const int64_t m = rel.size(0), k = rel.size(1);
  check_index(index, m, k, op);
  if (!mlps.w1.defined() || mlps.w1.dim() != 2 || mlps.w1.size(1) != 3 || !mlps.w3.defined() ||
      mlps.w2.size(0) != mlps.w1.size(0) || mlps.w3.size(1) != mlps.w1.size(0)) {
    throw ValueError(op, "WeightNet weights must be [H,3], [H,H], [J,H]");
  }
  const bool pos = mlps.e1.defined();
  if (pos && (mlps.e1.dim() != 2 || mlps.e1.size(1) != 3 || mlps.e2.size(1) != mlps.e1.size(0))) {
    throw ValueError(op, "positional embedding weights must be [P',3], [P,P']");
  }
  if (gate.defined() && (gate.dim() != 2 || gate.size(0) != m || gate.size(1) != k)) {
    throw ValueError(op, "gate must be [" + std::to_string(m) + "," + std::to_string(k) + "]");
  }
  check_index_range(index, features.size(0), op);
  torch::NoGradGuard no_grad;
  auto f32 = [](const torch::Tensor& t) { return t.detach().to(torch::kFloat).contiguous(); };
  const torch::Tensor feat = f32(features), r = f32(rel), idx = index.contiguous();
  const torch::Tensor g = gate.defined() ? f32(gate) : torch::Tensor();
  const torch::Tensor w1 = f32(mlps.w1), b1 = f32(mlps.b1), w2t = f32(mlps.w2.t()),
                      b2 = f32(mlps.b2), w3t = f32(mlps.w3.t()), b3 = f32(mlps.b3);
  torch::Tensor e1, c1, e2t, c2;
  if (pos) {
    e1 = f32(mlps.e1);
    c1 = f32(mlps.c1);
    e2t = f32(mlps.e2.t());
    c2 = f32(mlps.c2);
  }
  const int64_t hidden = w1.size(0), j = w3t.size(1), c = feat.size(1);
  const int64_t pos_hidden = pos ? e1.size(0) : 0, p = pos ? e2t.size(1) : 0;
  InferenceArgs a{feat.data_ptr<float>(),
                  r.data_ptr<float>(),
                  g.defined() ? g.data_ptr<float>() : nullptr,
                  idx.data_ptr<int64_t>(),
                  k,
                  c,
                  p,
                  hidden,
                  pos_hidden,
                  w1.data_ptr<float>(),
                  b1.data_ptr<float>(),
                  w2t.data_ptr<float>(),
                  b2.data_ptr<float>(),
                  w3t.data_ptr<float>(),
                  b3.data_ptr<float>(),
                  pos ? e1.data_ptr<float>() : nullptr,
                  pos ? c1.data_ptr<float>() : nullptr,
                  pos ? e2t.data_ptr<float>() : nullptr,
                  pos ? c2.data_ptr<float>() : nullptr};
  torch::Tensor out = torch::empty({m, j * (c + p)}, feat.options());
  float* o = out.data_ptr<float>();
  const bool simd = use_simd_clones();
  const int64_t scratch = (c + p) * j + 2 * hidden + j + pos_hidden + p;
  with_width(j, [&](auto width) {
    at::parallel_for(0, m, kGrain, [&](int64_t begin, int64_t end) {
      std::vector<float> buffer(static_cast<size_t>(scratch));
      if (simd) {
        inference_rows_simd(a, o, begin, end, width, buffer.data());
      } else {
        inference_rows_baseline(a, o, begin, end, width, buffer.data());
      }
    });
  });
  return out;
}

torch::Tensor gather_add(const torch::Tensor& q, const torch::Tensor& s, const torch::Tensor& r,
                         const torch::Tensor& index) {
  const char* op = "gather_add";
  if (q.dim() != 2 || s.dim() != 2 || q.size(1) != s.size(1)) {
    throw ValueError(op, "q [M,H] and s [N,H] must share H, got " + shape(q) + " and " + shape(s));
  }
  const auto dtype = q.scalar_type();
  if (dtype != torch::kFloat && dtype != torch::kDouble) {
    throw ValueError(op, "inputs must be float32 or float64");
  }
  check_float(q, dtype, "q", op);
  check_float(s, dtype, "s", op);
  check_index(index, q.size(0), index.dim() == 2 ? index.size(1) : -1, op);
  torch::Tensor rr = r;
  if (!rr.defined()) {
    rr = torch::empty({0}, q.options());
  } else {
    if (rr.dim() != 3 || rr.size(0) != q.size(0) || rr.size(1) != index.size(1) ||
        rr.size(2) != q.size(1)) {
      throw ValueError(op, "r must be [M,K,H], got " + shape(rr));
    }
    check_float(rr, dtype, "r", op);
  }
  check_index_range(index, s.size(0), op);
  return GatherAddFunction::apply(q, s, rr, index);
}

}  // namespace dynscope
