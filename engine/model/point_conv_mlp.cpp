// The PointConv aggregation with its WeightNet and positional embedding evaluated per neighbour
// inside the op, forward and backward (point_conv_aggregate_mlp): no [M,K,·] intermediate.
#include <torch/autograd.h>

#include <algorithm>
#include <cstring>
#include <vector>

#include "engine/core/error.h"
#include "engine/core/parallel.h"
#include "engine/model/fused_kernels.h"
#include "engine/model/fused_point_conv.h"
#include "engine/model/lanes.h"

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
  // The linear applied to each query's aggregate row (`[n_out][J·C']`); null: none, the rows
  // themselves are the output.
  const float* linear = nullptr;
  int64_t n_out = 0;
};

// The MLP sizes: filter width J, WeightNet hidden width H, embedding width P and its hidden width
// P'. A size given as a template argument (>= 0) is known at compile time, so every small loop
// below becomes a few whole vector operations; -1 reads it at run time.
template <int kJ, int kH, int kP, int kPH>
struct MlpDims {
  int64_t j, h, p, ph;
  constexpr int64_t J() const { return kJ >= 0 ? kJ : j; }
  constexpr int64_t H() const { return kH >= 0 ? kH : h; }
  constexpr int64_t P() const { return kP >= 0 ? kP : p; }
  constexpr int64_t PH() const { return kPH >= 0 ? kPH : ph; }
  constexpr Width<(kJ > 0 ? kJ : 0)> width() const { return {J()}; }
};

// Calls `f(MlpDims<...>)` with the sizes fixed at compile time where they are the model's
// (J = 16, H = 8, with the 8-wide embedding of the object convolutions or none, as in the
// relational ones).
template <typename F>
void with_mlp_dims(int64_t j, int64_t h, int64_t p, int64_t ph, F&& f) {
  if (j == 16 && h == 8 && p == 8 && ph == 8) return f(MlpDims<16, 8, 8, 8>{16, 8, 8, 8});
  if (j == 16 && h == 8 && p == 0) return f(MlpDims<16, 8, 0, 0>{16, 8, 0, 0});
  f(MlpDims<-1, -1, -1, -1>{j, h, p, ph});
}

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

// Rows [begin, end) of the inference aggregation; `scratch` holds inference_scratch floats.
template <class D>
DYNSCOPE_KERNEL_BODY void inference_rows_body(const InferenceArgs& a, float* out, int64_t begin,
                                              int64_t end, D d, float* scratch) {
  const int64_t j = d.J(), c = a.c, p = d.P(), ct = c + p, k = a.k, hd = d.H(), ph = d.PH();
  const auto width = d.width();
  float* row = scratch;  // the aggregate row when a linear follows
  float* acc = row + ct * j;
  float* h1 = acc + ct * j;
  float* h2 = h1 + hd;
  float* hk = h2 + hd;
  float* p1 = hk + j;
  float* pe = p1 + ph;
  for (int64_t q = begin; q < end; ++q) {
    std::fill(acc, acc + ct * j, 0.0f);
    int64_t nv = 0;
    for (int64_t n = 0; n < k; ++n) {
      const int64_t e = q * k + n;
      const int64_t src = a.index[e];
      if (src < 0) continue;
      ++nv;
      const float* r = a.rel + e * 3;
      first_layer(h1, r, a.w1, a.b1, hd);
      small_linear(h2, h1, hd, a.w2t, a.b2, hd, true);
      small_linear(hk, h2, hd, a.w3t, a.b3, j, false);
      if (a.gate) {
        const float g = a.gate[e];
#pragma omp simd
        for (int64_t jj = 0; jj < j; ++jj) hk[jj] *= g;
      }
      add_outer(acc, a.features + src * c, c, hk, width);
      if (p > 0) {
        first_layer(p1, r, a.e1, a.c1, ph);
        small_linear(pe, p1, ph, a.e2t, a.c2, p, false);
        add_outer(acc + c * j, pe, p, hk, width);
      }
    }
    if (a.linear && nv == 0) {  // a zero aggregate row, a zero linear
      std::fill(out + q * a.n_out, out + (q + 1) * a.n_out, 0.0f);
      continue;
    }
    float* o = a.linear ? row : out + q * j * ct;
    for (int64_t jj = 0; jj < j; ++jj) {
      for (int64_t cc = 0; cc < ct; ++cc) o[jj * ct + cc] = acc[cc * j + jj];
    }
    if (a.linear) apply_linear(out + q * a.n_out, row, j * ct, a.linear, a.n_out);
  }
}

// The model's MLP sizes (J = 16, H = 8, an 8-wide embedding with hidden width 8 or none) have
// inference_rows_blocked below; any other size runs inference_rows_body.
template <class D>
constexpr bool kBlockedDims = D{}.J() == 16 && D{}.H() == 8 &&
                              ((D{}.P() == 8 && D{}.PH() == 8) || D{}.P() == 0);

// The gathered rows' stride in inference_rows_blocked: C' rounded up to a multiple of 8.
constexpr int64_t blocked_row_stride(int64_t ct) { return (ct + 7) / 8 * 8; }

// The WeightNet's and the embedding's weights as whole vectors over their outputs.
struct BlockedWeights {
  Lanes8 w1[3], b1, w2[8], b2;  // w1[d] = column d of W1; w2[i] = row i of W2ᵀ
  Lanes16 w3[8], b3;            // w3[i] = row i of W3ᵀ
  Lanes8 w3h[8][2], b3h[2];     // the same in halves, for 16 registers of 8 floats
  Lanes8 e1[3], c1, e2[8], c2;  // the embedding's, likewise (unused without one)
};

DYNSCOPE_KERNEL_BODY BlockedWeights blocked_weights(const InferenceArgs& a, bool embedding) {
  BlockedWeights w{};
  for (int d = 0; d < 3; ++d) {
    for (int o = 0; o < 8; ++o) w.w1[d][o] = a.w1[3 * o + d];
  }
  load_lanes(w.b1, a.b1);
  for (int i = 0; i < 8; ++i) load_lanes(w.w2[i], a.w2t + 8 * i);
  load_lanes(w.b2, a.b2);
  for (int i = 0; i < 8; ++i) load_lanes(w.w3[i], a.w3t + 16 * i);
  load_lanes(w.b3, a.b3);
  for (int half = 0; half < 2; ++half) {
    for (int i = 0; i < 8; ++i) load_lanes(w.w3h[i][half], a.w3t + 16 * i + 8 * half);
    load_lanes(w.b3h[half], a.b3 + 8 * half);
  }
  if (embedding) {
    for (int d = 0; d < 3; ++d) {
      for (int o = 0; o < 8; ++o) w.e1[d][o] = a.e1[3 * o + d];
    }
    load_lanes(w.c1, a.c1);
    for (int i = 0; i < 8; ++i) load_lanes(w.e2[i], a.e2t + 8 * i);
    load_lanes(w.c2, a.c2);
  }
  return w;
}

// One neighbour's WeightNet hidden layers at relative position r: h2 = relu(W2·h1 + b2) and
// h1 = relu(W1·r + b1), left in `v1`, `v2` and in memory at `h1`, `h2` (8 floats each; the same
// place will do when only h2 is wanted).
DYNSCOPE_KERNEL_BODY void weightnet_hidden(const BlockedWeights& w, const float* r, float* h1,
                                           float* h2, Lanes8& v1, Lanes8& v2) {
  v1 = w.b1 + w.w1[0] * r[0] + w.w1[1] * r[1] + w.w1[2] * r[2];
  relu_lanes(v1);
  spill_lanes(h1, v1);
  v2 = w.b2;
#pragma GCC unroll 8
  for (int i = 0; i < 8; ++i) v2 += h1[i] * w.w2[i];
  relu_lanes(v2);
  spill_lanes(h2, v2);
}

// The whole WeightNet, h = W3·h2 + b3 after weightnet_hidden.
DYNSCOPE_KERNEL_BODY void weightnet(const BlockedWeights& w, const float* r, float* h1, float* h2,
                                    Lanes8& v1, Lanes8& v2, Lanes16& h) {
  weightnet_hidden(w, r, h1, h2, v1, v2);
  h = w.b3;
#pragma GCC unroll 8
  for (int i = 0; i < 8; ++i) h += h2[i] * w.w3[i];
}

// weightnet with h in halves of 8 (h[0, 8) in `lo`, h[8, 16) in `hi`): the same products in the
// same order, in registers of 8 floats.
DYNSCOPE_KERNEL_BODY void weightnet_halves(const BlockedWeights& w, const float* r, float* h1,
                                           float* h2, Lanes8& v1, Lanes8& v2, Lanes8& lo,
                                           Lanes8& hi) {
  weightnet_hidden(w, r, h1, h2, v1, v2);
  lo = w.b3h[0];
  hi = w.b3h[1];
#pragma GCC unroll 8
  for (int i = 0; i < 8; ++i) {
    lo += h2[i] * w.w3h[i][0];
    hi += h2[i] * w.w3h[i][1];
  }
}

// One neighbour's positional embedding: e = E2·p1 + c2 with p1 = relu(E1·r + c1), p1 left in `vp`
// and in memory at `p1`.
DYNSCOPE_KERNEL_BODY void embedding(const BlockedWeights& w, const float* r, float* p1, Lanes8& vp,
                                    Lanes8& e) {
  vp = w.c1 + w.e1[0] * r[0] + w.e1[1] * r[1] + w.e1[2] * r[2];
  relu_lanes(vp);
  spill_lanes(p1, vp);
  e = w.c2;
#pragma GCC unroll 8
  for (int i = 0; i < 8; ++i) e += p1[i] * w.e2[i];
}

// A valid neighbour's gathered row x `[C']`: its features, then with an embedding its embedding
// at relative position r (p1 left in memory at `p1`, as embedding() does).
template <bool kEmbedding>
DYNSCOPE_KERNEL_BODY void gather_neighbour_row(const InferenceArgs& a, const BlockedWeights& w,
                                               const float* r, int64_t src, float* x, float* p1) {
  std::copy(a.features + src * a.c, a.features + (src + 1) * a.c, x);
  if constexpr (kEmbedding) {
    Lanes8 vp, pe;
    embedding(w, r, p1, vp, pe);
    store_lanes(x + a.c, pe);
  }
}

// out[j·out_stride + c0 + i] = Σ_t h[t·16 + j] · x[t·stride + c0 + i] for j0 <= j < j0 + kRows
// and i < the lanes of V (16 or 8): one block of channels and filter rows of a query's
// aggregation over its nv gathered neighbour rows, the kRows sums kept in registers and each
// output written once.
template <class V, int kRows>
DYNSCOPE_KERNEL_BODY void aggregate_block(float* __restrict out, int64_t out_stride,
                                          const float* __restrict x, int64_t stride, int64_t c0,
                                          const float* __restrict h, int64_t nv, int j0) {
  V acc[kRows] = {};
  for (int64_t t = 0; t < nv; ++t) {
    V xt;
    load_lanes(xt, x + t * stride + c0);
    const float* ht = h + t * 16 + j0;
#pragma GCC unroll 16
    for (int jj = 0; jj < kRows; ++jj) acc[jj] += ht[jj] * xt;
  }
#pragma GCC unroll 16
  for (int jj = 0; jj < kRows; ++jj) store_lanes(out + (j0 + jj) * out_stride + c0, acc[jj]);
}

// A query's whole aggregate row `[16][cp]` (cp a multiple of 8) in blocks of channels: with wide
// registers (AVX-512: 32 of 16 floats) each block's 16 filter rows at once, 16 sums of 16 or 8
// channels; with 16 registers (AVX2 of 8 floats) half of the rows of an 8-channel block, 8 sums
// of 8 floats, so that the sums stay in registers (vectors of 16 floats, two registers each
// there, are moved through memory). Both add the same products in the same order.
template <bool kWide>
DYNSCOPE_KERNEL_BODY void aggregate_row(float* __restrict out, int64_t cp,
                                        const float* __restrict xs, const float* __restrict hs,
                                        int64_t nv) {
  int64_t c0 = 0;
  if constexpr (kWide) {
    for (; c0 + 16 <= cp; c0 += 16) aggregate_block<Lanes16, 16>(out, cp, xs, cp, c0, hs, nv, 0);
    if (c0 < cp) aggregate_block<Lanes8, 16>(out, cp, xs, cp, c0, hs, nv, 0);
  } else {
    for (; c0 < cp; c0 += 8) {
      aggregate_block<Lanes8, 8>(out, cp, xs, cp, c0, hs, nv, 0);
      aggregate_block<Lanes8, 8>(out, cp, xs, cp, c0, hs, nv, 8);
    }
  }
}

// inference_rows_body for the model's MLP sizes, arranged for the vector units. Per query, each
// valid neighbour's h (16 floats, gated) is computed as whole vectors, and its features and
// embedding are gathered into one row of C' floats; then the aggregation runs over blocks of 16
// (and 8) of the C' channels, each block's 16 filter rows summed in registers over the
// neighbours. The previous arrangement added every neighbour's outer product into an accumulator
// in memory (a load and a store per channel and neighbour) and transposed it into the output one
// float at a time. `scratch` holds inference_scratch floats.
template <class D, bool kWide>
DYNSCOPE_KERNEL_BODY void inference_rows_blocked(const InferenceArgs& a, float* out, int64_t begin,
                                                 int64_t end, D d, float* scratch) {
  constexpr bool kEmbedding = D{}.P() == 8;
  const int64_t c = a.c, ct = c + d.P(), k = a.k, cp = blocked_row_stride(ct);
  // C' not a multiple of 8 (the movi-a model's bottleneck leaves 6 and 12 channels): the rows
  // are padded by zeros to cp, aggregated whole and compacted after (or the linear's weight is
  // padded alike), so no channel is left to a scalar tail.
  const bool padded = cp != ct;
  const BlockedWeights w = blocked_weights(a, kEmbedding);
  float* hs = scratch;          // [K][16]: each valid neighbour's gated h
  float* xs = hs + k * 16;      // [K][cp]: its features and embedding, zero-padded
  float* hidden = xs + k * cp;  // [8]: a hidden layer's output, read one float at a time
  float* row = hidden + 8;      // [4][16·cp]: aggregate rows, of up to 4 queries for a linear
  std::vector<float> padded_linear;
  const float* linear = a.linear;
  if (linear && padded) {
    padded_linear.assign(static_cast<size_t>(a.n_out * 16 * cp), 0.0f);
    for (int64_t o = 0; o < a.n_out; ++o) {
      for (int64_t jj = 0; jj < 16; ++jj) {
        const float* from = a.linear + (o * 16 + jj) * ct;
        std::copy(from, from + ct, padded_linear.data() + (o * 16 + jj) * cp);
      }
    }
    linear = padded_linear.data();
  }
  // With a linear, the rows that have neighbours go through it four at a time (`rows` holds the
  // queries of the `pending` aggregate rows waiting in `row`); `four` takes the outputs of four
  // queries that are not consecutive.
  int64_t rows[4];
  int pending = 0;
  std::vector<float> four(linear ? static_cast<size_t>(4 * a.n_out) : 0);
  for (int64_t q = begin; q < end; ++q) {
    int64_t nv = 0;
    for (int64_t n = 0; n < k; ++n) {
      const int64_t e = q * k + n;
      const int64_t src = a.index[e];
      if (src < 0) continue;
      const float* r = a.rel + e * 3;
      Lanes8 v1, v2;
      if constexpr (kWide) {
        Lanes16 h;
        weightnet(w, r, hidden, hidden, v1, v2, h);
        if (a.gate) h *= a.gate[e];
        store_lanes(hs + nv * 16, h);
      } else {
        Lanes8 lo, hi;
        weightnet_halves(w, r, hidden, hidden, v1, v2, lo, hi);
        if (a.gate) {
          lo *= a.gate[e];
          hi *= a.gate[e];
        }
        store_lanes(hs + nv * 16, lo);
        store_lanes(hs + nv * 16 + 8, hi);
      }
      float* x = xs + nv * cp;
      gather_neighbour_row<kEmbedding>(a, w, r, src, x, hidden);
      std::fill(x + ct, x + cp, 0.0f);
      ++nv;
    }
    if (linear && nv == 0) {
      // No neighbour: the aggregate row is zero and so is its linear (no bias inside the op).
      // Relational lists leave most rows so.
      std::fill(out + q * a.n_out, out + (q + 1) * a.n_out, 0.0f);
      continue;
    }
    // The aggregate row, [16][cp]: straight into the output when it has that layout.
    float* o = (linear || padded) ? row + pending * 16 * cp : out + q * 16 * ct;
    aggregate_row<kWide>(o, cp, xs, hs, nv);
    if (!linear) {
      if (padded) {
        for (int64_t jj = 0; jj < 16; ++jj) {
          std::copy(o + jj * cp, o + jj * cp + ct, out + (q * 16 + jj) * ct);
        }
      }
      continue;
    }
    rows[pending++] = q;
    if (pending == 4) {
      float* y = rows[3] == rows[0] + 3 ? out + rows[0] * a.n_out : four.data();
      // Four sums of 16-float vectors per row with wide registers, two of 8 with 16 registers.
      if constexpr (kWide) {
        apply_linear4<Lanes16, 4>(y, row, 16 * cp, linear, a.n_out);
      } else {
        apply_linear4<Lanes8, 2>(y, row, 16 * cp, linear, a.n_out);
      }
      if (y == four.data()) {
        for (int r = 0; r < 4; ++r) {
          std::copy(four.data() + r * a.n_out, four.data() + (r + 1) * a.n_out,
                    out + rows[r] * a.n_out);
        }
      }
      pending = 0;
    }
  }
  for (int r = 0; r < pending; ++r) {
    apply_linear(out + rows[r] * a.n_out, row + r * 16 * cp, 16 * cp, linear, a.n_out);
  }
}

// Floats of the inference rows' scratch: for inference_rows_body the aggregate row and the
// accumulator (C'·J each), h1 and h2, h, p1 and e; for inference_rows_blocked K rows of
// 16 + blocked_row_stride(C'), 8 for a hidden layer and four aggregate rows of 16 such.
int64_t inference_scratch(int64_t ct, int64_t j, int64_t hd, int64_t p, int64_t ph, int64_t k) {
  return std::max(2 * ct * j + 2 * hd + j + ph + p,
                  k * (16 + blocked_row_stride(ct)) + 8 + 4 * 16 * blocked_row_stride(ct));
}

template <class D, bool kWide>
DYNSCOPE_KERNEL_BODY void inference_rows(const InferenceArgs& a, float* out, int64_t begin,
                                         int64_t end, D d, float* scratch) {
  if constexpr (kBlockedDims<D>) {
    inference_rows_blocked<D, kWide>(a, out, begin, end, d, scratch);
  } else {
    inference_rows_body(a, out, begin, end, d, scratch);
  }
}

template <class D>
void inference_rows_baseline(const InferenceArgs& a, float* out, int64_t begin, int64_t end, D d,
                             float* scratch) {
  inference_rows<D, false>(a, out, begin, end, d, scratch);  // SSE2: 16 registers
}

template <class D>
DYNSCOPE_ISA_CLONES void inference_rows_simd(const InferenceArgs& a, float* out, int64_t begin,
                                             int64_t end, D d, float* scratch) {
  if (wide_vector_registers()) {
    inference_rows<D, true>(a, out, begin, end, d, scratch);
  } else {
    inference_rows<D, false>(a, out, begin, end, d, scratch);
  }
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

// dx[i] = (wt[i,:] · dy) where the ReLU output x[i] > 0, else 0: the input gradient of a linear
// stored transposed (wt `[in][out]`) whose input came out of a ReLU.
DYNSCOPE_KERNEL_BODY void linear_input_grad(float* __restrict dx, const float* __restrict wt,
                                            const float* __restrict x, int64_t in,
                                            const float* __restrict dy, int64_t out) {
  for (int64_t i = 0; i < in; ++i) {
    const float* __restrict w = wt + i * out;
    float s = 0.0f;
#pragma omp simd reduction(+ : s)
    for (int64_t o = 0; o < out; ++o) s += w[o] * dy[o];
    dx[i] = x[i] > 0.0f ? s : 0.0f;
  }
}

// Weight and bias gradients of a linear over n edges at once: dwt[i,o] += Σ_e x[e,i] dy[e,o] and
// db[o] += Σ_e dy[e,o], for x `[n][in]` and dy `[n][out]`. Each row of dwt is read and written
// once per call, its sum over the edges kept in registers.
DYNSCOPE_KERNEL_BODY void linear_weight_grad(float* __restrict dwt, float* __restrict db,
                                             const float* __restrict x, int64_t in,
                                             const float* __restrict dy, int64_t out, int64_t n) {
  constexpr int64_t kMaxOut = 32;
  float acc[kMaxOut];
  for (int64_t o0 = 0; o0 < out; o0 += kMaxOut) {
    const int64_t w = std::min(kMaxOut, out - o0);
    for (int64_t i = 0; i < in; ++i) {
      float* __restrict row = dwt + i * out + o0;
#pragma omp simd
      for (int64_t o = 0; o < w; ++o) acc[o] = row[o];
      for (int64_t e = 0; e < n; ++e) {
        const float v = x[e * in + i];
        const float* __restrict g = dy + e * out + o0;
#pragma omp simd
        for (int64_t o = 0; o < w; ++o) acc[o] += v * g[o];
      }
#pragma omp simd
      for (int64_t o = 0; o < w; ++o) row[o] = acc[o];
    }
#pragma omp simd
    for (int64_t o = 0; o < w; ++o) acc[o] = db[o0 + o];
    for (int64_t e = 0; e < n; ++e) {
      const float* __restrict g = dy + e * out + o0;
#pragma omp simd
      for (int64_t o = 0; o < w; ++o) acc[o] += g[o];
    }
#pragma omp simd
    for (int64_t o = 0; o < w; ++o) db[o0 + o] = acc[o];
  }
}

// linear_weight_grad for 8 inputs and kOut (8 or 16) outputs in vectors of 8 floats: four inputs'
// rows of dwt at a time, kOut / 8 vectors each, summed over the edges in registers (8 of them for
// 16 outputs), where the loop over a run-time width kept its sums in memory. The same sums in the
// same order.
template <int kOut>
DYNSCOPE_KERNEL_BODY void linear_weight_grad8(float* __restrict dwt, float* __restrict db,
                                              const float* __restrict x, const float* __restrict dy,
                                              int64_t n) {
  constexpr int kV = kOut / 8;
  for (int i0 = 0; i0 < 8; i0 += 4) {
    Lanes8 acc[4][kV];
#pragma GCC unroll 4
    for (int u = 0; u < 4; ++u) {
      for (int v = 0; v < kV; ++v) load_lanes(acc[u][v], dwt + (i0 + u) * kOut + 8 * v);
    }
    for (int64_t e = 0; e < n; ++e) {
      Lanes8 g[kV];
      for (int v = 0; v < kV; ++v) load_lanes(g[v], dy + e * kOut + 8 * v);
#pragma GCC unroll 4
      for (int u = 0; u < 4; ++u) {
        const float s = x[e * 8 + i0 + u];
        for (int v = 0; v < kV; ++v) acc[u][v] += s * g[v];
      }
    }
#pragma GCC unroll 4
    for (int u = 0; u < 4; ++u) {
      for (int v = 0; v < kV; ++v) store_lanes(dwt + (i0 + u) * kOut + 8 * v, acc[u][v]);
    }
  }
  Lanes8 b[kV];
  for (int v = 0; v < kV; ++v) load_lanes(b[v], db + 8 * v);
  for (int64_t e = 0; e < n; ++e) {
    for (int v = 0; v < kV; ++v) {
      Lanes8 g;
      load_lanes(g, dy + e * kOut + 8 * v);
      b[v] += g;
    }
  }
  for (int v = 0; v < kV; ++v) store_lanes(db + 8 * v, b[v]);
}

// Weight and bias gradients of first_layer (`[n_out,3]`) over n edges: da `[n][n_out]` is the
// pre-activation gradient of each edge and rel + edge[e]·3 its relative position.
DYNSCOPE_KERNEL_BODY void first_layer_weight_grad(float* __restrict dw, float* __restrict db,
                                                  const float* __restrict rel,
                                                  const int64_t* __restrict edge,
                                                  const float* __restrict da, int64_t n_out,
                                                  int64_t n) {
  for (int64_t e = 0; e < n; ++e) {
    const float* r = rel + edge[e] * 3;
    const float* __restrict g = da + e * n_out;
    for (int64_t o = 0; o < n_out; ++o) {
      db[o] += g[o];
      for (int d3 = 0; d3 < 3; ++d3) dw[o * 3 + d3] += g[o] * r[d3];
    }
  }
}

// acc += s · p[0, 16).
DYNSCOPE_KERNEL_BODY void add_scaled16(Lanes16& acc, float s, const float* p) {
  Lanes16 v;
  std::memcpy(&v, p, sizeof v);
  acc += s * v;
}

// The padded width of a C'-wide row: a whole number of Lanes16.
constexpr int64_t padded16(int64_t n) { return (n + 15) / 16 * 16; }

// y[0, w) = Σ_j s[j] · rows[j·w, (j+1)·w) for w a multiple of 16, the sums kept in registers
// (two chains, so the additions overlap) and each y written once.
DYNSCOPE_KERNEL_BODY void combine_rows(float* __restrict y, const float* __restrict rows, int64_t w,
                                       const float* __restrict s, int64_t j) {
  for (int64_t c0 = 0; c0 < w; c0 += 16) {
    Lanes16 even = {}, odd = {};
    int64_t jj = 0;
    for (; jj + 1 < j; jj += 2) {
      add_scaled16(even, s[jj], rows + jj * w + c0);
      add_scaled16(odd, s[jj + 1], rows + (jj + 1) * w + c0);
    }
    if (jj < j) add_scaled16(even, s[jj], rows + jj * w + c0);
    const Lanes16 sum = even + odd;
    std::memcpy(y + c0, &sum, sizeof sum);
  }
}

// One query's output gradient g (`[J][C']`) as the backward kernels read it: transposed, gt
// `[C'][J]`, and with its rows padded by zeros to cp >= C', gp `[J][cp]`.
DYNSCOPE_KERNEL_BODY void transpose_and_pad(const float* __restrict g, int64_t j, int64_t ct,
                                            float* __restrict gt, float* __restrict gp,
                                            int64_t cp) {
  for (int64_t jj = 0; jj < j; ++jj) {
    for (int64_t cc = 0; cc < ct; ++cc) gt[cc * j + jj] = g[jj * ct + cc];
    std::copy(g + jj * ct, g + (jj + 1) * ct, gp + jj * cp);
    std::fill(gp + jj * cp + ct, gp + (jj + 1) * cp, 0.0f);
  }
}

// Gradients of the MLP aggregation for rows [begin, end). Per query: each valid neighbour's h and
// e are recomputed and its feature, gate and hidden-layer gradients computed; then the weight
// gradients of all the query's neighbours are added at once. `d_feat` is this worker's `[N,C]`
// buffer (or null), `dw` its weight-gradient buffer, `d_gate` `[M,K]` (or null). `scratch` holds
// mlp_grad_scratch floats, `edges` K entries.
template <class D>
DYNSCOPE_KERNEL_BODY void mlp_grad_rows_body(const InferenceArgs& a, const float* grad,
                                             float* d_feat, float* d_gate, float* dw,
                                             const MlpGradLayout& lay, int64_t begin, int64_t end,
                                             D d, float* scratch, int64_t* edges) {
  const int64_t j = d.J(), c = a.c, p = d.P(), ct = c + p, k = a.k;
  const int64_t hd = d.H(), ph = d.PH();
  const auto width = d.width();
  const int64_t cp = padded16(ct);
  float* gt = scratch;      // [C'][J]
  float* gp = gt + ct * j;  // [J][C' padded]: G with zeroed padding
  float* x = gp + j * cp;   // [C']
  float* dx = x + ct;       // [C' padded]
  float* hk = dx + cp;      // [J]: h before the gate
  float* hg = hk + j;       // [J]: h after the gate
  // Per valid neighbour of the query, row by row:
  float* h1 = hg + j;       // [K][H]
  float* h2 = h1 + k * hd;  // [K][H]
  float* dh = h2 + k * hd;  // [K][J]: gradient of h before the gate
  float* dh2 = dh + k * j;  // [K][H]
  float* dh1 = dh2 + k * hd;
  float* p1 = dh1 + k * hd;  // [K][P']
  float* de = p1 + k * ph;   // [K][P]: gradient of the embedding
  float* dp1 = de + k * p;   // [K][P']
  for (int64_t q = begin; q < end; ++q) {
    const float* g = grad + q * j * ct;
    transpose_and_pad(g, j, ct, gt, gp, cp);
    int64_t nv = 0;
    for (int64_t n = 0; n < k; ++n) {
      const int64_t e = q * k + n;
      const int64_t src = a.index[e];
      if (src < 0) continue;
      const float* r = a.rel + e * 3;
      const float gate = a.gate ? a.gate[e] : 1.0f;
      float* h1e = h1 + nv * hd;
      float* h2e = h2 + nv * hd;
      float* dhe = dh + nv * j;
      first_layer(h1e, r, a.w1, a.b1, hd);
      small_linear(h2e, h1e, hd, a.w2t, a.b2, hd, true);
      small_linear(hk, h2e, hd, a.w3t, a.b3, j, false);
      std::copy(a.features + src * c, a.features + (src + 1) * c, x);
      if (p > 0) {
        first_layer(p1 + nv * ph, r, a.e1, a.c1, ph);
        small_linear(x + c, p1 + nv * ph, ph, a.e2t, a.c2, p, false);
      }
      // d(gated h)[j] = Σ_c G[j,c] x[c]; dx[c] = Σ_j gate·h[j] G[j,c].
      std::fill(dhe, dhe + j, 0.0f);
      add_filter_grad(dhe, gt, x, ct, width);
#pragma omp simd
      for (int64_t jj = 0; jj < j; ++jj) hg[jj] = gate * hk[jj];
      combine_rows(dx, gp, cp, hg, j);
      if (d_feat) {
        float* __restrict dst = d_feat + src * c;
#pragma omp simd
        for (int64_t cc = 0; cc < c; ++cc) dst[cc] += dx[cc];
      }
      if (d_gate) {
        float dg = 0.0f;
        for (int64_t jj = 0; jj < j; ++jj) dg += dhe[jj] * hk[jj];
        d_gate[e] = dg;
      }
#pragma omp simd
      for (int64_t jj = 0; jj < j; ++jj) dhe[jj] *= gate;
      // WeightNet: h = W3 h2 + b3, h2 = relu(W2 h1 + b2), h1 = relu(W1 r + b1).
      linear_input_grad(dh2 + nv * hd, a.w3t, h2e, hd, dhe, j);
      linear_input_grad(dh1 + nv * hd, a.w2t, h1e, hd, dh2 + nv * hd, hd);
      if (p > 0) {
        // e = E2 p1 + c2, p1 = relu(E1 r + c1); de = dx[C:].
        std::copy(dx + c, dx + ct, de + nv * p);
        linear_input_grad(dp1 + nv * ph, a.e2t, p1 + nv * ph, ph, de + nv * p, p);
      }
      edges[nv++] = e;
    }
    if (nv == 0) continue;
    linear_weight_grad(dw + lay.w3t, dw + lay.b3, h2, hd, dh, j, nv);
    linear_weight_grad(dw + lay.w2t, dw + lay.b2, h1, hd, dh2, hd, nv);
    first_layer_weight_grad(dw + lay.w1, dw + lay.b1, a.rel, edges, dh1, hd, nv);
    if (p > 0) {
      linear_weight_grad(dw + lay.e2t, dw + lay.c2, p1, ph, de, p, nv);
      first_layer_weight_grad(dw + lay.e1, dw + lay.c1, a.rel, edges, dp1, ph, nv);
    }
  }
}

// The rows of W3 (`[16][8]`), W2 and E2 (`[8][8]`) as vectors over their inputs, for the input
// gradients dx = Σ_o dy[o] · W[o,:] of mlp_grad_rows_blocked.
struct BlockedGradWeights {
  Lanes8 w3[16], w2[8], e2[8];
};

DYNSCOPE_KERNEL_BODY BlockedGradWeights blocked_grad_weights(const InferenceArgs& a,
                                                             bool embedding) {
  BlockedGradWeights g{};
  for (int o = 0; o < 16; ++o) {
    for (int i = 0; i < 8; ++i) g.w3[o][i] = a.w3t[i * 16 + o];
  }
  for (int o = 0; o < 8; ++o) {
    for (int i = 0; i < 8; ++i) g.w2[o][i] = a.w2t[i * 8 + o];
  }
  if (embedding) {
    for (int o = 0; o < 8; ++o) {
      for (int i = 0; i < 8; ++i) g.e2[o][i] = a.e2t[i * 8 + o];
    }
  }
  return g;
}

// dx[c0, c0 + lanes of V) = Σ_j s[j] · g[j·C' + c0, ...) over the 16 filter rows, in two chains.
template <class V>
DYNSCOPE_KERNEL_BODY void combine_block(float* __restrict dx, const float* __restrict g, int64_t ct,
                                        int64_t c0, const float* __restrict s) {
  V even = {}, odd = {};
#pragma GCC unroll 8
  for (int jj = 0; jj < 16; jj += 2) {
    V a, b;
    load_lanes(a, g + jj * ct + c0);
    load_lanes(b, g + (jj + 1) * ct + c0);
    even += s[jj] * a;
    odd += s[jj + 1] * b;
  }
  const V sum = even + odd;
  store_lanes(dx + c0, sum);
}

// mlp_grad_rows_body for the model's MLP sizes, arranged for the vector units as
// inference_rows_blocked: every per-neighbour vector (h1, h2, h, the embedding's, their
// gradients) is computed whole, a layer's inputs read back from memory as broadcasts; the input
// gradients of the MLPs' linears run over W's rows (Σ_o dy[o]·W[o,:]) instead of one dot product
// per input; the filter gradient sums over the channels in four chains; the feature gradient
// sums G's rows (padded by zeros to a multiple of 8 channels) in blocks of 16 and 8. The same
// per-query weight gradients follow. With 16 vector registers (!kWide) every vector of 16 floats
// is kept as two of 8 (h, the filter gradient's chains, G's rows), as in inference_rows_blocked.
template <class D, bool kWide>
DYNSCOPE_KERNEL_BODY void mlp_grad_rows_blocked(const InferenceArgs& a, const float* grad,
                                                float* d_feat, float* d_gate, float* dw,
                                                const MlpGradLayout& lay, int64_t begin,
                                                int64_t end, D d, float* scratch, int64_t* edges) {
  constexpr bool kEmbedding = D{}.P() == 8;
  const int64_t c = a.c, ct = c + d.P(), k = a.k;
  const BlockedWeights w = blocked_weights(a, kEmbedding);
  const BlockedGradWeights wg = blocked_grad_weights(a, kEmbedding);
  const int64_t cp = blocked_row_stride(ct);
  float* gt = scratch;       // [C'][16]: G transposed
  float* gp = gt + ct * 16;  // [16][cp]: G with its rows padded by zeros to a multiple of 8
  float* x = gp + 16 * cp;   // [C' + 8]: the neighbour's features and embedding
  float* dx = x + ct + 8;    // [C' + 8]: their gradient
  float* hg = dx + ct + 8;   // [16]: h after the gate
  float* h1 = hg + 16;       // [K][8]
  float* h2 = h1 + k * 8;    // [K][8]
  float* dh = h2 + k * 8;    // [K][16]: gradient of h before the gate
  float* dh2 = dh + k * 16;  // [K][8]
  float* dh1 = dh2 + k * 8;  // [K][8]
  float* p1 = dh1 + k * 8;   // [K][8]
  float* de = p1 + k * 8;    // [K][8]: gradient of the embedding
  float* dp1 = de + k * 8;   // [K][8]
  for (int64_t q = begin; q < end; ++q) {
    const float* g = grad + q * 16 * ct;
    transpose_and_pad(g, 16, ct, gt, gp, cp);
    int64_t nv = 0;
    for (int64_t n = 0; n < k; ++n) {
      const int64_t e = q * k + n;
      const int64_t src = a.index[e];
      if (src < 0) continue;
      const float* r = a.rel + e * 3;
      const float gate = a.gate ? a.gate[e] : 1.0f;
      Lanes8 v1, v2;
      float* dhe = dh + nv * 16;
      gather_neighbour_row<kEmbedding>(a, w, r, src, x, p1 + nv * 8);
      if constexpr (kWide) {
        Lanes16 h;
        weightnet(w, r, h1 + nv * 8, h2 + nv * 8, v1, v2, h);
        const Lanes16 gated = h * gate;
        spill_lanes(hg, gated);
        // d(gated h)[j] = Σ_c G[j,c] x[c], four chains over the channels.
        Lanes16 chain[4] = {};
        int64_t cc = 0;
        for (; cc + 4 <= ct; cc += 4) {
#pragma GCC unroll 4
          for (int u = 0; u < 4; ++u) {
            Lanes16 row;
            load_lanes(row, gt + (cc + u) * 16);
            chain[u] += x[cc + u] * row;
          }
        }
        for (; cc < ct; ++cc) {
          Lanes16 row;
          load_lanes(row, gt + cc * 16);
          chain[0] += x[cc] * row;
        }
        const Lanes16 dgated = (chain[0] + chain[1]) + (chain[2] + chain[3]);
        // dx[c] = Σ_j gate·h[j] G[j,c].
        int64_t c0 = 0;
        for (; c0 + 16 <= cp; c0 += 16) combine_block<Lanes16>(dx, gp, cp, c0, hg);
        if (c0 < cp) combine_block<Lanes8>(dx, gp, cp, c0, hg);
        if (d_gate) d_gate[e] = lane_sum(dgated * h);
        spill_lanes(dhe, dgated * gate);
      } else {
        Lanes8 lo, hi;
        weightnet_halves(w, r, h1 + nv * 8, h2 + nv * 8, v1, v2, lo, hi);
        spill_lanes(hg, lo * gate);
        spill_lanes(hg + 8, hi * gate);
        // The same four chains, each in halves.
        Lanes8 chain_lo[4] = {}, chain_hi[4] = {};
        int64_t cc = 0;
        for (; cc + 4 <= ct; cc += 4) {
#pragma GCC unroll 4
          for (int u = 0; u < 4; ++u) {
            Lanes8 row_lo, row_hi;
            load_lanes(row_lo, gt + (cc + u) * 16);
            load_lanes(row_hi, gt + (cc + u) * 16 + 8);
            chain_lo[u] += x[cc + u] * row_lo;
            chain_hi[u] += x[cc + u] * row_hi;
          }
        }
        for (; cc < ct; ++cc) {
          Lanes8 row_lo, row_hi;
          load_lanes(row_lo, gt + cc * 16);
          load_lanes(row_hi, gt + cc * 16 + 8);
          chain_lo[0] += x[cc] * row_lo;
          chain_hi[0] += x[cc] * row_hi;
        }
        const Lanes8 d_lo = (chain_lo[0] + chain_lo[1]) + (chain_lo[2] + chain_lo[3]);
        const Lanes8 d_hi = (chain_hi[0] + chain_hi[1]) + (chain_hi[2] + chain_hi[3]);
        for (int64_t c0 = 0; c0 < cp; c0 += 8) combine_block<Lanes8>(dx, gp, cp, c0, hg);
        if (d_gate) d_gate[e] = lane_sum(d_lo * lo) + lane_sum(d_hi * hi);
        spill_lanes(dhe, d_lo * gate);
        spill_lanes(dhe + 8, d_hi * gate);
      }
      if (d_feat) {
        float* __restrict dst = d_feat + src * c;
#pragma omp simd
        for (int64_t i = 0; i < c; ++i) dst[i] += dx[i];
      }
      // WeightNet: h = W3 h2 + b3, h2 = relu(W2 h1 + b2), h1 = relu(W1 r + b1).
      Lanes8 g2 = {};
#pragma GCC unroll 16
      for (int o = 0; o < 16; ++o) g2 += dhe[o] * wg.w3[o];
      g2 = v2 > 0.0f ? g2 : Lanes8{};
      spill_lanes(dh2 + nv * 8, g2);
      Lanes8 g1 = {};
#pragma GCC unroll 8
      for (int o = 0; o < 8; ++o) g1 += dh2[nv * 8 + o] * wg.w2[o];
      g1 = v1 > 0.0f ? g1 : Lanes8{};
      store_lanes(dh1 + nv * 8, g1);
      if constexpr (kEmbedding) {
        // e = E2 p1 + c2, p1 = relu(E1 r + c1); de = dx[C:].
        float* dee = de + nv * 8;
        std::copy(dx + c, dx + ct, dee);
        Lanes8 gp = {};
#pragma GCC unroll 8
        for (int o = 0; o < 8; ++o) gp += dee[o] * wg.e2[o];
        Lanes8 vp;
        load_lanes(vp, p1 + nv * 8);
        gp = vp > 0.0f ? gp : Lanes8{};
        store_lanes(dp1 + nv * 8, gp);
      }
      edges[nv++] = e;
    }
    if (nv == 0) continue;
    if constexpr (kWide) {
      linear_weight_grad(dw + lay.w3t, dw + lay.b3, h2, 8, dh, 16, nv);
      linear_weight_grad(dw + lay.w2t, dw + lay.b2, h1, 8, dh2, 8, nv);
    } else {
      linear_weight_grad8<16>(dw + lay.w3t, dw + lay.b3, h2, dh, nv);
      linear_weight_grad8<8>(dw + lay.w2t, dw + lay.b2, h1, dh2, nv);
    }
    first_layer_weight_grad(dw + lay.w1, dw + lay.b1, a.rel, edges, dh1, 8, nv);
    if constexpr (kEmbedding) {
      if constexpr (kWide) {
        linear_weight_grad(dw + lay.e2t, dw + lay.c2, p1, 8, de, 8, nv);
      } else {
        linear_weight_grad8<8>(dw + lay.e2t, dw + lay.c2, p1, de, nv);
      }
      first_layer_weight_grad(dw + lay.e1, dw + lay.c1, a.rel, edges, dp1, 8, nv);
    }
  }
}

// Floats of mlp_grad_rows_body's scratch.
int64_t mlp_grad_scratch(int64_t ct, int64_t j, int64_t hd, int64_t p, int64_t ph, int64_t k) {
  // mlp_grad_rows_blocked's: G transposed and padded, x and dx (padded by 8), gated h, and per
  // neighbour h1, h2, dh, dh2, dh1, p1, de and dp1.
  const int64_t blocked =
      ct * 16 + 16 * blocked_row_stride(ct) + 2 * (ct + 8) + 16 + k * (7 * 8 + 16);
  return std::max(blocked, ct * j + j * padded16(ct) + ct + padded16(ct) + 2 * j +
                               k * (4 * hd + j + 2 * ph + p));
}

template <class D, bool kWide>
DYNSCOPE_KERNEL_BODY void mlp_grad_rows(const InferenceArgs& a, const float* grad, float* d_feat,
                                        float* d_gate, float* dw, const MlpGradLayout& lay,
                                        int64_t begin, int64_t end, D d, float* scratch,
                                        int64_t* edges) {
  if constexpr (kBlockedDims<D>) {
    mlp_grad_rows_blocked<D, kWide>(a, grad, d_feat, d_gate, dw, lay, begin, end, d, scratch,
                                    edges);
  } else {
    mlp_grad_rows_body(a, grad, d_feat, d_gate, dw, lay, begin, end, d, scratch, edges);
  }
}

template <class D>
void mlp_grad_rows_baseline(const InferenceArgs& a, const float* grad, float* d_feat, float* d_gate,
                            float* dw, const MlpGradLayout& lay, int64_t begin, int64_t end, D d,
                            float* scratch, int64_t* edges) {
  mlp_grad_rows<D, false>(a, grad, d_feat, d_gate, dw, lay, begin, end, d, scratch, edges);
}

template <class D>
DYNSCOPE_ISA_CLONES void mlp_grad_rows_simd(const InferenceArgs& a, const float* grad,
                                            float* d_feat, float* d_gate, float* dw,
                                            const MlpGradLayout& lay, int64_t begin, int64_t end,
                                            D d, float* scratch, int64_t* edges) {
  if (wide_vector_registers()) {
    mlp_grad_rows<D, true>(a, grad, d_feat, d_gate, dw, lay, begin, end, d, scratch, edges);
  } else {
    mlp_grad_rows<D, false>(a, grad, d_feat, d_gate, dw, lay, begin, end, d, scratch, edges);
  }
}

// What the MLP aggregation's kernels read, prepared once per call: contiguous float inputs and the
// transposed hidden weights.
// `t` itself when contiguous (no LibTorch call), else a contiguous copy.
torch::Tensor contiguous(const torch::Tensor& t) { return t.is_contiguous() ? t : t.contiguous(); }

// The same, undefined for an undefined or empty tensor (the absent gate or embedding).
torch::Tensor contiguous_or_none(const torch::Tensor& t) {
  if (!t.defined() || t.numel() == 0) return torch::Tensor();
  return contiguous(t);
}

// A linear's weight `[out,in]` as the kernels read it, `[in][out]`, copied by a plain loop: three
// such small transposes per call were a dozen LibTorch calls per convolution.
std::vector<float> transposed(const torch::Tensor& w) {
  const torch::Tensor c = contiguous_or_none(w);
  if (!c.defined()) return {};
  const int64_t out = c.size(0), in = c.size(1);
  const float* p = c.data_ptr<float>();
  std::vector<float> t(static_cast<size_t>(out * in));
  for (int64_t o = 0; o < out; ++o) {
    for (int64_t i = 0; i < in; ++i) t[static_cast<size_t>(i * out + o)] = p[o * in + i];
  }
  return t;
}

struct MlpPrepared {
  torch::Tensor features, rel, gate, index, w1, b1, b2, b3, e1, c1, c2;
  std::vector<float> w2t, w3t, e2t;  // `[in][out]` copies of w2, w3 and e2
  int64_t p = 0;                     // embedding width (e2's rows), 0 without one
  InferenceArgs args() const {
    auto ptr = [](const torch::Tensor& t) -> const float* {
      return t.defined() ? t.data_ptr<float>() : nullptr;
    };
    auto vec = [](const std::vector<float>& v) -> const float* {
      return v.empty() ? nullptr : v.data();
    };
    const bool pos = e1.defined();
    return {ptr(features),
            ptr(rel),
            ptr(gate),
            index.data_ptr<int64_t>(),
            index.size(1),
            features.size(1),
            p,
            w1.size(0),
            pos ? e1.size(0) : 0,
            ptr(w1),
            ptr(b1),
            vec(w2t),
            ptr(b2),
            vec(w3t),
            ptr(b3),
            ptr(e1),
            ptr(c1),
            vec(e2t),
            ptr(c2)};
  }
};

MlpPrepared prepare_mlp(const torch::Tensor& features, const torch::Tensor& gate,
                        const std::vector<torch::Tensor>& w, const torch::Tensor& rel,
                        const torch::Tensor& index) {
  // Empty tensors stand for absent ones (the gate, the embedding).
  MlpPrepared m;
  m.features = contiguous(features);
  m.rel = contiguous(rel);
  m.gate = contiguous_or_none(gate);
  m.index = contiguous(index);
  m.w1 = contiguous(w[0]);
  m.b1 = contiguous(w[1]);
  m.w2t = transposed(w[2]);
  m.b2 = contiguous(w[3]);
  m.w3t = transposed(w[4]);
  m.b3 = contiguous(w[5]);
  m.e1 = contiguous_or_none(w[6]);
  m.c1 = contiguous_or_none(w[7]);
  m.e2t = transposed(w[8]);
  m.c2 = contiguous_or_none(w[9]);
  m.p = m.e1.defined() ? w[8].size(0) : 0;
  return m;
}

// The inference rows over all M queries, parallel over rows: `[M, J·C']`, or `[M, n_out]` when
// `a` carries a linear.
torch::Tensor run_inference_rows(const InferenceArgs& a, int64_t m, int64_t j,
                                 const torch::TensorOptions& options) {
  const int64_t ct = a.c + a.p;
  torch::Tensor out = torch::empty({m, a.linear ? a.n_out : j * ct}, options);
  float* o = out.data_ptr<float>();
  const bool simd = use_simd_clones();
  const int64_t scratch = inference_scratch(ct, j, a.hidden, a.p, a.pos_hidden, a.k);
  with_mlp_dims(j, a.hidden, a.p, a.pos_hidden, [&](auto dims) {
    parallel_chunks(m, kGrain, true, [&](int64_t begin, int64_t end) {
      std::vector<float> buffer(static_cast<size_t>(scratch));
      if (simd) {
        inference_rows_simd(a, o, begin, end, dims, buffer.data());
      } else {
        inference_rows_baseline(a, o, begin, end, dims, buffer.data());
      }
    });
  });
  return out;
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
    const torch::Tensor out = run_inference_rows(a, rel.size(0), w3.size(0), features.options());
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
    const int64_t scratch = mlp_grad_scratch(ct, j, a.hidden, a.p, a.pos_hidden, k);
    with_mlp_dims(j, a.hidden, a.p, a.pos_hidden, [&](auto dims) {
      parallel_chunks(part.parts, 1, true, [&](int64_t first, int64_t last) {
        std::vector<float> buffer(static_cast<size_t>(scratch));
        std::vector<int64_t> edges(static_cast<size_t>(k));
        for (int64_t wk = first; wk < last; ++wk) {
          float* d_feat = want_feat ? feat_buffers.data_ptr<float>() + wk * n_src * a.c : nullptr;
          float* dg = want_gate ? d_gate.data_ptr<float>() : nullptr;
          float* dwp = dw.data_ptr<float>() + wk * lay.size;
          if (simd) {
            mlp_grad_rows_simd(a, grad.data_ptr<float>(), d_feat, dg, dwp, lay, part.begin(wk),
                               part.end(wk), dims, buffer.data(), edges.data());
          } else {
            mlp_grad_rows_baseline(a, grad.data_ptr<float>(), d_feat, dg, dwp, lay, part.begin(wk),
                                   part.end(wk), dims, buffer.data(), edges.data());
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

namespace {

// The checks shared by point_conv_aggregate_mlp and point_conv_aggregate_mlp_linear.
void check_mlp_arguments(const torch::Tensor& features, const torch::Tensor& rel,
                         const EdgeMlps& mlps, const torch::Tensor& gate,
                         const torch::Tensor& index, const char* op) {
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
}

}  // namespace

torch::Tensor point_conv_aggregate_mlp(const torch::Tensor& features, const torch::Tensor& rel,
                                       const EdgeMlps& mlps, const torch::Tensor& gate,
                                       const torch::Tensor& index) {
  check_mlp_arguments(features, rel, mlps, gate, index, "point_conv_aggregate_mlp");
  // LibTorch's custom functions need every tensor argument defined: absent ones travel empty.
  auto or_empty = [&](const torch::Tensor& t) {
    return t.defined() ? t : torch::empty({0}, features.options());
  };
  return MlpAggregateFunction::apply(features, or_empty(gate), mlps.w1, mlps.b1, mlps.w2, mlps.b2,
                                     mlps.w3, mlps.b3, or_empty(mlps.e1), or_empty(mlps.c1),
                                     or_empty(mlps.e2), or_empty(mlps.c2), rel, index);
}

torch::Tensor point_conv_aggregate_mlp_linear(const torch::Tensor& features,
                                              const torch::Tensor& rel, const EdgeMlps& mlps,
                                              const torch::Tensor& gate, const torch::Tensor& index,
                                              const torch::Tensor& weight) {
  const char* op = "point_conv_aggregate_mlp_linear";
  check_mlp_arguments(features, rel, mlps, gate, index, op);
  const int64_t j = mlps.w3.size(0);
  const int64_t p = mlps.e1.defined() ? mlps.e2.size(0) : 0;
  const int64_t n_in = j * (features.size(1) + p);
  if (weight.dim() != 2 || weight.size(1) != n_in || weight.scalar_type() != torch::kFloat) {
    throw ValueError(
        op, "weight must be float32 [C_out," + std::to_string(n_in) + "], got " + shape(weight));
  }
  bool records_grad = false;
  if (torch::GradMode::is_enabled()) {
    for (const torch::Tensor& t : {features, gate, mlps.w1, mlps.b1, mlps.w2, mlps.b2, mlps.w3,
                                   mlps.b3, mlps.e1, mlps.c1, mlps.e2, mlps.c2, weight}) {
      records_grad = records_grad || (t.defined() && t.requires_grad());
    }
  }
  if (records_grad) {
    return torch::mm(point_conv_aggregate_mlp(features, rel, mlps, gate, index), weight.t());
  }
  const std::vector<torch::Tensor> w{mlps.w1, mlps.b1, mlps.w2, mlps.b2, mlps.w3,
                                     mlps.b3, mlps.e1, mlps.c1, mlps.e2, mlps.c2};
  const MlpPrepared prep = prepare_mlp(features, gate, w, rel, index);
  const torch::Tensor linear = contiguous(weight);
  InferenceArgs a = prep.args();
  a.linear = linear.data_ptr<float>();
  a.n_out = weight.size(0);
  return run_inference_rows(a, rel.size(0), j, features.options());
}

}  // namespace dynscope
