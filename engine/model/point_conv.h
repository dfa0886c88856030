// Efficient PointConv (paper eq. 2): y_0 = W_l vec(Σ_k h(p_k − p_0) x_kᵀ) over a neighbour list.
#pragma once

#include <torch/nn/module.h>
#include <torch/nn/modules/container/sequential.h>
#include <torch/nn/modules/linear.h>
#include <torch/nn/pimpl.h>

#include "engine/model/fused_point_conv.h"
#include "engine/model/neighbor_tensors.h"

namespace dynscope {

/// Sizes and variants of a PointConv layer.
struct PointConvOptions {
  PointConvOptions(int64_t in_channels, int64_t out_channels)
      : in_channels_(in_channels), out_channels_(out_channels) {}
  /// Feature channels C_in of the source points (without the positional embedding).
  TORCH_ARG(int64_t, in_channels);
  /// Output channels C_out.
  TORCH_ARG(int64_t, out_channels);
  /// Width c_mid of the WeightNet output h(·).
  TORCH_ARG(int64_t, c_mid) = 16;
  /// Hidden width of the WeightNet 3 → hidden → hidden → c_mid.
  TORCH_ARG(int64_t, weight_hidden) = 8;
  /// Width of the positional embedding e(p_k − p_0) appended to x_k (0: none, paper eq. 3).
  TORCH_ARG(int64_t, pos_channels) = 0;
  /// Divide the sum by the number of valid neighbours (relational convolutions, paper eq. 4).
  TORCH_ARG(bool, normalize) = false;
  /// Relative positions are divided by this length before h and e (keeps their inputs O(1)).
  TORCH_ARG(double, position_scale) = 1.0;
};

/// Efficient PointConv. Masked neighbours contribute nothing (h is multiplied by the mask) and a
/// query with no valid neighbour outputs exactly zero. Submodules: "weightnet", "pos_embed" (only
/// when pos_channels > 0), "linear" (W_l: C·c_mid → C_out, where C = in_channels + pos_channels
/// and input column m·C + c multiplies h_m x_c).
class PointConvImpl : public torch::nn::Module {
 public:
  explicit PointConvImpl(const PointConvOptions& options);

  /// `query` `[M,3]` and `source` `[N,3]` float64 positions, `features` `[N,C_in]` float32,
  /// `neighbors` `[M,K]` into source → `[M,C_out]` float32.
  torch::Tensor forward(const torch::Tensor& query, const torch::Tensor& source,
                        const torch::Tensor& features, const NeighborTensors& neighbors);

  /// The filter weights h(p_k − p_0) `[M,K,c_mid]` the forward pass uses (zero where masked).
  torch::Tensor filter_weights(const torch::Tensor& query, const torch::Tensor& source,
                               const NeighborTensors& neighbors);

  const PointConvOptions& options() const { return options_; }
  /// The WeightNet and positional-embedding weights as point_conv_aggregate_mlp reads them, their
  /// first layers multiplied by `position_factor` (the MLPs of relative positions r then read
  /// r·position_factor).
  EdgeMlps edge_mlps(double position_factor = 1.0) const;

  torch::nn::Sequential weightnet{nullptr};
  torch::nn::Sequential pos_embed{nullptr};
  torch::nn::Linear linear{nullptr};

 private:
  // The unfused reference formulation (ConvImplementation::kUnfused).
  torch::Tensor forward_unfused(const torch::Tensor& query, const torch::Tensor& source,
                                const torch::Tensor& features, const NeighborTensors& neighbors);

  // Float64 and ConvImplementation::kFusedComposed: WeightNet and embedding as LibTorch ops,
  // then the aggregation op.
  torch::Tensor aggregate_with_autograd(const torch::Tensor& features, const torch::Tensor& rel,
                                        const NeighborTensors& neighbors);

  PointConvOptions options_;
};
TORCH_MODULE(PointConv);

}  // namespace dynscope
