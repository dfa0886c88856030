// Fused PointConv aggregation and message gather: CPU kernels parallel over query points, with
// hand-written backward passes (LibTorch's bmm on M tiny matrices dispatches one matrix at a time).
#include "engine/model/fused_point_conv.h"

#include <ATen/Dispatch.h>
#include <torch/autograd.h>

#include <atomic>
#include <cmath>
#include <string>
#include <vector>

#include "engine/core/error.h"
#include "engine/core/parallel.h"
#include "engine/model/conv_implementation.h"
#include "engine/model/fused_kernels.h"

namespace dynscope {
namespace {

using namespace fused_detail;  // the kernels' shared helpers (fused_kernels.h)

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
DYNSCOPE_ISA_CLONES void aggregate_rows_simd(const AggregateArgs<T>& a, T* out, int64_t begin,
                                             int64_t end, Width<kJ> width, T* acc) {
  aggregate_rows_body(a, out, begin, end, width, acc);
}

template <typename T, int kJ>
void aggregate_forward(const T* features, const T* edge, const T* h, const int64_t* index, T* out,
                       int64_t m, int64_t k, int64_t c, int64_t p, Width<kJ> width) {
  const AggregateArgs<T> args{features, edge, h, index, k, c, p};
  const bool simd = use_simd_clones();
  parallel_chunks(m, kGrain, true, [&](int64_t begin, int64_t end) {
    std::vector<T> acc(static_cast<size_t>((c + p) * width()));
    if (simd) {
      aggregate_rows_simd(args, out, begin, end, width, acc.data());
    } else {
      aggregate_rows_baseline(args, out, begin, end, width, acc.data());
    }
  });
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
DYNSCOPE_ISA_CLONES void aggregate_grad_rows_simd(const AggregateArgs<T>& a,
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
  parallel_chunks(part.parts, 1, true, [&](int64_t first, int64_t last) {
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
DYNSCOPE_ISA_CLONES void gather_add_rows_simd(const T* q, const T* s, const T* r,
                                              const int64_t* index, T* out, int64_t begin,
                                              int64_t end, int64_t k, int64_t hdim) {
  gather_add_rows_body(q, s, r, index, out, begin, end, k, hdim);
}

template <typename T>
void gather_add_forward(const T* q, const T* s, const T* r, const int64_t* index, T* out, int64_t m,
                        int64_t k, int64_t hdim) {
  const bool simd = use_simd_clones();
  parallel_chunks(m, kGrain, true, [&](int64_t begin, int64_t end) {
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
  parallel_chunks(part.parts, 1, true, [&](int64_t first, int64_t last) {
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

// Rows [begin, end) of relu(layer_norm(x)): two passes over each row (mean, then the squared
// deviations, as a two-pass variance is exact to rounding), then the affine map and the ReLU.
DYNSCOPE_KERNEL_BODY void layer_norm_relu_body(const float* __restrict x, const float* __restrict w,
                                               const float* __restrict b, float* __restrict y,
                                               int64_t c, float eps, int64_t begin, int64_t end) {
  const float inv_c = 1.0f / static_cast<float>(c);
  for (int64_t r = begin; r < end; ++r) {
    const float* __restrict xr = x + r * c;
    float* __restrict yr = y + r * c;
    float sum = 0.0f;
#pragma omp simd reduction(+ : sum)
    for (int64_t i = 0; i < c; ++i) sum += xr[i];
    const float mean = sum * inv_c;
    float sq = 0.0f;
#pragma omp simd reduction(+ : sq)
    for (int64_t i = 0; i < c; ++i) sq += (xr[i] - mean) * (xr[i] - mean);
    const float rstd = 1.0f / std::sqrt(sq * inv_c + eps);
#pragma omp simd
    for (int64_t i = 0; i < c; ++i) {
      const float v = (xr[i] - mean) * rstd * w[i] + b[i];
      yr[i] = v > 0.0f ? v : 0.0f;
    }
  }
}

DYNSCOPE_ISA_CLONES void layer_norm_relu_simd(const float* x, const float* w, const float* b,
                                              float* y, int64_t c, float eps, int64_t begin,
                                              int64_t end) {
  layer_norm_relu_body(x, w, b, y, c, eps, begin, end);
}

void layer_norm_relu_baseline(const float* x, const float* w, const float* b, float* y, int64_t c,
                              float eps, int64_t begin, int64_t end) {
  layer_norm_relu_body(x, w, b, y, c, eps, begin, end);
}

std::atomic<ConvImplementation> g_implementation{ConvImplementation::kFused};

}  // namespace

const char* fused_kernel_isa() { return isa_level(); }

const char* fused_kernel_blocking() { return wide_vector_registers() ? "wide" : "narrow"; }

ConvImplementation conv_implementation() { return g_implementation.load(); }

void set_conv_implementation(ConvImplementation implementation) {
  g_implementation.store(implementation);
}

torch::Tensor layer_norm_relu(const torch::Tensor& x, const torch::Tensor& weight,
                              const torch::Tensor& bias, double eps) {
  const int64_t c = x.dim() == 2 ? x.size(1) : -1;
  const bool records_grad = torch::GradMode::is_enabled() &&
                            (x.requires_grad() || weight.requires_grad() || bias.requires_grad());
  const bool fused = !records_grad && conv_implementation() != ConvImplementation::kUnfused &&
                     x.scalar_type() == torch::kFloat && weight.scalar_type() == torch::kFloat &&
                     bias.scalar_type() == torch::kFloat && x.device().is_cpu() && c > 0 &&
                     weight.numel() == c && bias.numel() == c;
  if (!fused) return torch::layer_norm(x, {x.size(-1)}, weight, bias, eps).relu_();
  const torch::Tensor xc = x.contiguous(), wc = weight.contiguous(), bc = bias.contiguous();
  torch::Tensor y = torch::empty_like(xc);
  const float* xp = xc.data_ptr<float>();
  const float* wp = wc.data_ptr<float>();
  const float* bp = bc.data_ptr<float>();
  float* yp = y.data_ptr<float>();
  const bool simd = use_simd_clones();
  const auto e = static_cast<float>(eps);
  parallel_chunks(x.size(0), 4 * kGrain, true, [&](int64_t begin, int64_t end) {
    if (simd) {
      layer_norm_relu_simd(xp, wp, bp, yp, c, e, begin, end);
    } else {
      layer_norm_relu_baseline(xp, wp, bp, yp, c, e, begin, end);
    }
  });
  return y;
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
