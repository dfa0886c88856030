// Fused PointConv aggregation Σ_k h_k ⊗ x_k over a neighbour list, with a hand-written backward.
#pragma once

#include <torch/types.h>

#include "engine/model/neighbor_tensors.h"

namespace dynscope {

/// The aggregation of the efficient PointConv (paper eq. 2) as one op, parallel over query points:
///   out[m, j·C' + c] = Σ_k h[m,k,j] · x_{m,k}[c],   x_{m,k} = [features[index[m,k]] ; edge[m,k]]
/// with C' = C + P. `features` `[N,C]`, `edge` `[M,K,P]` per-neighbour channels (e.g. the
/// positional embedding; undefined for none), `h` `[M,K,J]` filter weights, `index` int64 `[M,K]`
/// into features with −1 for masked entries, which contribute nothing and get zero gradient.
/// Float32 or float64 (all floating inputs of one dtype), CPU. Returns `[M, J·C']`; differentiable
/// in features, edge and h without materialising the `[M,K,C']` gather. Throws ValueError on
/// shape, dtype or index mismatch.
torch::Tensor point_conv_aggregate(const torch::Tensor& features, const torch::Tensor& edge,
                                   const torch::Tensor& h, const torch::Tensor& index);

/// The two small per-edge MLPs of a PointConv as plain weights: the WeightNet
/// h = W3·relu(W2·relu(W1·r + b1) + b2) + b3 (r → J) and, when `e1` is defined, the positional
/// embedding e = E2·relu(E1·r + c1) + c2 (r → P). Shapes as torch::nn::Linear stores them
/// (`[out, in]` weights, `[out]` biases).
struct EdgeMlps {
  torch::Tensor w1, b1, w2, b2, w3, b3;
  torch::Tensor e1, c1, e2, c2;
};

/// point_conv_aggregate(features, e(r), h(r) · gate, index) with the edge MLPs evaluated per
/// neighbour inside the aggregation, forward and backward, so no `[M,K,·]` intermediate is
/// written or saved: the backward recomputes h and e per neighbour. `rel` `[M,K,3]` float32
/// relative positions (already scaled; no gradient flows into them), `gate` `[M,K]` or undefined.
/// Differentiable in features, gate and every MLP weight. Float32, CPU. Throws ValueError on
/// shape, dtype or index mismatch.
torch::Tensor point_conv_aggregate_mlp(const torch::Tensor& features, const torch::Tensor& rel,
                                       const EdgeMlps& mlps, const torch::Tensor& gate,
                                       const torch::Tensor& index);

/// point_conv_aggregate_mlp(features, rel, mlps, gate, index) · weightᵀ: the aggregation and the
/// linear after it (`weight` `[C_out, J·C']` float32, no bias), `[M, C_out]`. Without gradients
/// to record (no grad mode, or no input requiring one) each query's aggregate row is multiplied
/// inside the op, so the `[M, J·C']` aggregate is never written; otherwise it is the two ops, and
/// differentiable as they are. Throws ValueError as point_conv_aggregate_mlp and on a weight of
/// another shape.
torch::Tensor point_conv_aggregate_mlp_linear(const torch::Tensor& features,
                                              const torch::Tensor& rel, const EdgeMlps& mlps,
                                              const torch::Tensor& gate, const torch::Tensor& index,
                                              const torch::Tensor& weight);

/// Gathered edge inputs for message passing, as one op: out[m,k] = q[m] + s[index[m,k]] + r[m,k]
/// for valid entries and 0 where index is −1. `q` `[M,H]`, `s` `[N,H]`, `r` `[M,K,H]` (undefined:
/// none). Float32 or float64, CPU; differentiable in q, s and r. Throws ValueError on mismatch.
torch::Tensor gather_add(const torch::Tensor& q, const torch::Tensor& s, const torch::Tensor& r,
                         const torch::Tensor& index);

/// relu(layer_norm(x)) over the last dimension of `x` `[M,C]` with `weight` and `bias` `[C]`, as
/// torch::layer_norm followed by ReLU. Without gradients to record (no grad mode, or no input
/// requiring one) and on float32 input, one pass per row in the instruction-set clone of the CPU,
/// parallel over rows; otherwise, and for ConvImplementation::kUnfused, the two LibTorch ops.
torch::Tensor layer_norm_relu(const torch::Tensor& x, const torch::Tensor& weight,
                              const torch::Tensor& bias, double eps);

/// The list's index with −1 wherever its mask is false (the form the fused ops read); prepared
/// lists are returned as they are (prepare() writes them in that form).
torch::Tensor masked_index(const NeighborTensors& neighbors);

}  // namespace dynscope
