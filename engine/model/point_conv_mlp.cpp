// The PointConv aggregation with its WeightNet and positional embedding evaluated per neighbour
// inside the op, forward and backward (point_conv_aggregate_mlp): no [M,K,·] intermediate.
#include <ATen/Parallel.h>
#include <torch/autograd.h>

#include <vector>

#include "engine/core/error.h"
#include "engine/model/fused_kernels.h"
#include "engine/model/fused_point_conv.h"

namespace dynscope {
namespace {

using namespace fused_detail;  // the kernels' shared helpers (fused_kernels.h)

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

// Offsets of the weight gradients in one flat per-worker buffer, in the transposed layouts the
// kernels read (w2t, w3t, e2t), transposed back by the caller.
struct MlpGradLayout {
  int64_t w1, b1, w2t, b2, w3t, b3, e1, c1, e2t, c2, size;
  MlpGradLayout(int64_t h, int64_t j, int64_t ph, int64_t p) {
    int64_t at = 0;
    auto take = [&at](int64_t n) {
      const int64_t o = at;
      at += n;
      return o;
    };
    w1 = take(h * 3);
    b1 = take(h);
    w2t = take(h * h);
    b2 = take(h);
    w3t = take(h * j);
    b3 = take(j);
    e1 = take(ph * 3);
    c1 = take(ph);
    e2t = take(ph * p);
    c2 = take(p);
    size = at;
  }
};

// Backward of y = Wᵀ-stored linear (wt `[in][out]`) on a ReLU output x: accumulates dwt += x ⊗ dy
// and db += dy, and writes dx = (wt · dy) where x > 0 (the ReLU that produced x), else 0.
DYNSCOPE_KERNEL_BODY void linear_backward(float* __restrict dwt, float* __restrict db,
                                          const float* __restrict wt, const float* __restrict x,
                                          int64_t in, const float* __restrict dy, int64_t out,
                                          float* __restrict dx) {
  for (int64_t i = 0; i < in; ++i) {
    float* __restrict row = dwt + i * out;
    const float* __restrict w = wt + i * out;
    const float v = x[i];
    float s = 0.0f;
#pragma omp simd reduction(+ : s)
    for (int64_t o = 0; o < out; ++o) {
      row[o] += v * dy[o];
      s += w[o] * dy[o];
    }
    dx[i] = v > 0.0f ? s : 0.0f;
  }
  for (int64_t o = 0; o < out; ++o) db[o] += dy[o];
}

// Backward of first_layer's weights (`[n,3]`) and biases for the pre-activation gradient da.
DYNSCOPE_KERNEL_BODY void first_layer_backward(float* __restrict dw, float* __restrict db,
                                               const float* __restrict r,
                                               const float* __restrict da, int64_t n) {
  for (int64_t o = 0; o < n; ++o) {
    db[o] += da[o];
    for (int d3 = 0; d3 < 3; ++d3) dw[o * 3 + d3] += da[o] * r[d3];
  }
}

// Gradients of the MLP aggregation for rows [begin, end): recomputes each neighbour's h and e,
// then backpropagates through the outer product, the gate and both MLPs. `d_feat` is this
// worker's `[N,C]` buffer (or null), `dw` its weight-gradient buffer, `d_gate` `[M,K]` (or null).
template <int kJ>
DYNSCOPE_KERNEL_BODY void mlp_grad_rows_body(const InferenceArgs& a, const float* grad,
                                             float* d_feat, float* d_gate, float* dw,
                                             const MlpGradLayout& lay, int64_t begin, int64_t end,
                                             Width<kJ> width, float* scratch) {
  const int64_t j = width(), c = a.c, p = a.p, ct = c + p, k = a.k;
  const int64_t hd = a.hidden, ph = a.pos_hidden;
  float* gt = scratch;     // [C'][J]
  float* x = gt + ct * j;  // [C']
  float* dx = x + ct;      // [C']
  float* h1 = dx + ct;
  float* h2 = h1 + hd;
  float* hk = h2 + hd;  // h before the gate
  float* dh = hk + j;
  float* dh2 = dh + j;
  float* dh1 = dh2 + hd;
  float* p1 = dh1 + hd;
  float* dp1 = p1 + ph;
  for (int64_t q = begin; q < end; ++q) {
    const float* g = grad + q * j * ct;
    for (int64_t jj = 0; jj < j; ++jj) {
      for (int64_t cc = 0; cc < ct; ++cc) gt[cc * j + jj] = g[jj * ct + cc];
    }
    for (int64_t n = 0; n < k; ++n) {
      const int64_t e = q * k + n;
      const int64_t src = a.index[e];
      if (src < 0) continue;
      const float* r = a.rel + e * 3;
      const float gate = a.gate ? a.gate[e] : 1.0f;
      first_layer(h1, r, a.w1, a.b1, hd);
      small_linear(h2, h1, hd, a.w2t, a.b2, hd, true);
      small_linear(hk, h2, hd, a.w3t, a.b3, j, false);
      std::copy(a.features + src * c, a.features + (src + 1) * c, x);
      if (p > 0) {
        first_layer(p1, r, a.e1, a.c1, ph);
        small_linear(x + c, p1, ph, a.e2t, a.c2, p, false);
      }
      // d(gated h)[j] = Σ_c G[j,c] x[c]; dx[c] = Σ_j gate·h[j] G[j,c].
      std::fill(dh, dh + j, 0.0f);
      add_filter_grad(dh, gt, x, ct, width);
      std::fill(dx, dx + ct, 0.0f);
      for (int64_t jj = 0; jj < j; ++jj) {
        const float hj = gate * hk[jj];
        const float* __restrict row = g + jj * ct;
#pragma omp simd
        for (int64_t cc = 0; cc < ct; ++cc) dx[cc] += hj * row[cc];
      }
      if (d_feat) {
        float* __restrict dst = d_feat + src * c;
#pragma omp simd
        for (int64_t cc = 0; cc < c; ++cc) dst[cc] += dx[cc];
      }
      if (d_gate) {
        float dg = 0.0f;
        for (int64_t jj = 0; jj < j; ++jj) dg += dh[jj] * hk[jj];
        d_gate[e] = dg;
      }
      for (int64_t jj = 0; jj < j; ++jj) dh[jj] *= gate;
      // WeightNet: h = W3 h2 + b3, h2 = relu(W2 h1 + b2), h1 = relu(W1 r + b1).
      linear_backward(dw + lay.w3t, dw + lay.b3, a.w3t, h2, hd, dh, j, dh2);
      linear_backward(dw + lay.w2t, dw + lay.b2, a.w2t, h1, hd, dh2, hd, dh1);
      first_layer_backward(dw + lay.w1, dw + lay.b1, r, dh1, hd);
      if (p > 0) {
        // e = E2 p1 + c2, p1 = relu(E1 r + c1); de = dx[C:].
        linear_backward(dw + lay.e2t, dw + lay.c2, a.e2t, p1, ph, dx + c, p, dp1);
        first_layer_backward(dw + lay.e1, dw + lay.c1, r, dp1, ph);
      }
    }
  }
}

template <int kJ>
void mlp_grad_rows_baseline(const InferenceArgs& a, const float* grad, float* d_feat, float* d_gate,
                            float* dw, const MlpGradLayout& lay, int64_t begin, int64_t end,
                            Width<kJ> width, float* scratch) {
  mlp_grad_rows_body(a, grad, d_feat, d_gate, dw, lay, begin, end, width, scratch);
}

template <int kJ>
DYNSCOPE_SIMD_CLONES void mlp_grad_rows_simd(const InferenceArgs& a, const float* grad,
                                             float* d_feat, float* d_gate, float* dw,
                                             const MlpGradLayout& lay, int64_t begin, int64_t end,
                                             Width<kJ> width, float* scratch) {
  mlp_grad_rows_body(a, grad, d_feat, d_gate, dw, lay, begin, end, width, scratch);
}

// What the MLP aggregation's kernels read, prepared once per call: contiguous float inputs and the
// transposed hidden weights.
struct MlpPrepared {
  torch::Tensor features, rel, gate, index, w1, b1, w2t, b2, w3t, b3, e1, c1, e2t, c2;
  InferenceArgs args() const {
    auto ptr = [](const torch::Tensor& t) -> const float* {
      return t.defined() ? t.data_ptr<float>() : nullptr;
    };
    const bool pos = e1.defined();
    return {ptr(features),
            ptr(rel),
            ptr(gate),
            index.data_ptr<int64_t>(),
            index.size(1),
            features.size(1),
            pos ? e2t.size(1) : 0,
            w1.size(0),
            pos ? e1.size(0) : 0,
            ptr(w1),
            ptr(b1),
            ptr(w2t),
            ptr(b2),
            ptr(w3t),
            ptr(b3),
            ptr(e1),
            ptr(c1),
            ptr(e2t),
            ptr(c2)};
  }
};

MlpPrepared prepare_mlp(const torch::Tensor& features, const torch::Tensor& gate,
                        const std::vector<torch::Tensor>& w, const torch::Tensor& rel,
                        const torch::Tensor& index) {
  // Empty tensors stand for absent ones (the gate, the embedding).
  auto c = [](const torch::Tensor& t) {
    return t.defined() && t.numel() > 0 ? t.contiguous() : torch::Tensor();
  };
  auto ct = [](const torch::Tensor& t) {
    return t.defined() && t.numel() > 0 ? t.t().contiguous() : torch::Tensor();
  };
  return {features.contiguous(),
          rel.contiguous(),
          c(gate),
          index.contiguous(),
          w[0].contiguous(),
          w[1].contiguous(),
          w[2].t().contiguous(),
          w[3].contiguous(),
          w[4].t().contiguous(),
          w[5].contiguous(),
          c(w[6]),
          c(w[7]),
          ct(w[8]),
          c(w[9])};
}

struct MlpAggregateFunction : torch::autograd::Function<MlpAggregateFunction> {
  static torch::Tensor forward(AutogradContext* ctx, torch::Tensor features, torch::Tensor gate,
                               torch::Tensor w1, torch::Tensor b1, torch::Tensor w2,
                               torch::Tensor b2, torch::Tensor w3, torch::Tensor b3,
                               torch::Tensor e1, torch::Tensor c1, torch::Tensor e2,
                               torch::Tensor c2, torch::Tensor rel, torch::Tensor index) {
    const std::vector<torch::Tensor> w{w1, b1, w2, b2, w3, b3, e1, c1, e2, c2};
    const MlpPrepared prep = prepare_mlp(features, gate, w, rel, index);
    const InferenceArgs a = prep.args();
    const int64_t m = rel.size(0), j = w3.size(0), ct = a.c + a.p;
    torch::Tensor out = torch::empty({m, j * ct}, features.options());
    float* o = out.data_ptr<float>();
    const bool simd = use_simd_clones();
    const int64_t scratch = ct * j + 2 * a.hidden + j + a.pos_hidden + a.p;
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
    ctx->save_for_backward({features, gate, w1, b1, w2, b2, w3, b3, e1, c1, e2, c2, rel, index});
    return out;
  }

  static tensor_list backward(AutogradContext* ctx, tensor_list grads) {
    const auto v = ctx->get_saved_variables();
    const std::vector<torch::Tensor> w(v.begin() + 2, v.begin() + 12);
    const MlpPrepared prep = prepare_mlp(v[0], v[1], w, v[12], v[13]);
    const InferenceArgs a = prep.args();
    const torch::Tensor grad = grads[0].contiguous();
    const int64_t m = v[12].size(0), k = v[12].size(1), j = v[6].size(0), n_src = v[0].size(0);
    const MlpGradLayout lay(a.hidden, j, a.pos_hidden, a.p);
    const Partition part = partition(m);
    const bool want_feat = ctx->needs_input_grad(0),
               want_gate = prep.gate.defined() && ctx->needs_input_grad(1);
    torch::Tensor feat_buffers, d_gate;
    if (want_feat) feat_buffers = torch::zeros({part.parts, n_src, a.c}, grad.options());
    if (want_gate) d_gate = torch::zeros({m, k}, grad.options());
    torch::Tensor dw = torch::zeros({part.parts, lay.size}, grad.options());
    const bool simd = use_simd_clones();
    const int64_t ct = a.c + a.p;
    const int64_t scratch = ct * j + 2 * ct + 3 * a.hidden + 2 * j + a.hidden + 2 * a.pos_hidden;
    with_width(j, [&](auto width) {
      at::parallel_for(0, part.parts, 1, [&](int64_t first, int64_t last) {
        std::vector<float> buffer(static_cast<size_t>(scratch));
        for (int64_t wk = first; wk < last; ++wk) {
          float* d_feat = want_feat ? feat_buffers.data_ptr<float>() + wk * n_src * a.c : nullptr;
          float* dg = want_gate ? d_gate.data_ptr<float>() : nullptr;
          float* dwp = dw.data_ptr<float>() + wk * lay.size;
          if (simd) {
            mlp_grad_rows_simd(a, grad.data_ptr<float>(), d_feat, dg, dwp, lay, part.begin(wk),
                               part.end(wk), width, buffer.data());
          } else {
            mlp_grad_rows_baseline(a, grad.data_ptr<float>(), d_feat, dg, dwp, lay, part.begin(wk),
                                   part.end(wk), width, buffer.data());
          }
        }
      });
    });
    const torch::Tensor d = part.parts == 1 ? dw[0] : dw.sum(0);
    auto piece = [&](int64_t offset, std::initializer_list<int64_t> sizes, int index) {
      if (!ctx->needs_input_grad(index)) return torch::Tensor();
      int64_t n = 1;
      for (int64_t s : sizes) n *= s;
      return d.narrow(0, offset, n).reshape(sizes).clone();
    };
    const int64_t hd = a.hidden, ph = a.pos_hidden, p = a.p;
    tensor_list out(14);
    if (want_feat) out[0] = part.parts == 1 ? feat_buffers[0] : feat_buffers.sum(0);
    out[1] = d_gate;
    out[2] = piece(lay.w1, {hd, 3}, 2);
    out[3] = piece(lay.b1, {hd}, 3);
    const torch::Tensor dw2t = piece(lay.w2t, {hd, hd}, 4);
    out[4] = dw2t.defined() ? dw2t.t().contiguous() : dw2t;
    out[5] = piece(lay.b2, {hd}, 5);
    const torch::Tensor dw3t = piece(lay.w3t, {hd, j}, 6);
    out[6] = dw3t.defined() ? dw3t.t().contiguous() : dw3t;
    out[7] = piece(lay.b3, {j}, 7);
    if (prep.e1.defined()) {
      out[8] = piece(lay.e1, {ph, 3}, 8);
      out[9] = piece(lay.c1, {ph}, 9);
      const torch::Tensor de2t = piece(lay.e2t, {ph, p}, 10);
      out[10] = de2t.defined() ? de2t.t().contiguous() : de2t;
      out[11] = piece(lay.c2, {p}, 11);
    }
    return out;
  }
};

}  // namespace

torch::Tensor point_conv_aggregate_mlp(const torch::Tensor& features, const torch::Tensor& rel,
                                       const EdgeMlps& mlps, const torch::Tensor& gate,
                                       const torch::Tensor& index) {
  const char* op = "point_conv_aggregate_mlp";
  if (features.dim() != 2 || rel.dim() != 3 || rel.size(2) != 3) {
    throw ValueError(op, "features must be [N,C] and rel [M,K,3], got " + shape(features) +
                             " and " + shape(rel));
  }
  check_float(features, torch::kFloat, "features", op);
  check_float(rel, torch::kFloat, "rel", op);
  const int64_t m = rel.size(0), k = rel.size(1);
  check_index(index, m, k, op);
  auto is = [](const torch::Tensor& t, std::initializer_list<int64_t> sizes) {
    return t.defined() && t.sizes() == torch::IntArrayRef(sizes) &&
           t.scalar_type() == torch::kFloat;
  };
  const int64_t hd = mlps.w1.defined() ? mlps.w1.size(0) : 0;
  const int64_t j = mlps.w3.defined() ? mlps.w3.size(0) : 0;
  if (!is(mlps.w1, {hd, 3}) || !is(mlps.b1, {hd}) || !is(mlps.w2, {hd, hd}) || !is(mlps.b2, {hd}) ||
      !is(mlps.w3, {j, hd}) || !is(mlps.b3, {j})) {
    throw ValueError(op, "WeightNet weights must be float32 [H,3], [H], [H,H], [H], [J,H], [J]");
  }
  if (mlps.e1.defined()) {
    const int64_t ph = mlps.e1.size(0), p = mlps.e2.defined() ? mlps.e2.size(0) : 0;
    if (!is(mlps.e1, {ph, 3}) || !is(mlps.c1, {ph}) || !is(mlps.e2, {p, ph}) || !is(mlps.c2, {p})) {
      throw ValueError(op, "embedding weights must be float32 [P',3], [P'], [P,P'], [P]");
    }
  }
  if (gate.defined() && !is(gate, {m, k})) {
    throw ValueError(op,
                     "gate must be float32 [" + std::to_string(m) + "," + std::to_string(k) + "]");
  }
  check_index_range(index, features.size(0), op);
  // LibTorch's custom functions need every tensor argument defined: absent ones travel empty.
  auto or_empty = [&](const torch::Tensor& t) {
    return t.defined() ? t : torch::empty({0}, features.options());
  };
  return MlpAggregateFunction::apply(features, or_empty(gate), mlps.w1, mlps.b1, mlps.w2, mlps.b2,
                                     mlps.w3, mlps.b3, or_empty(mlps.e1), or_empty(mlps.c1),
                                     or_empty(mlps.e2), or_empty(mlps.c2), rel, index);
}

}  // namespace dynscope
