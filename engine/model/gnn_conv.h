// DPI-style message passing (the GNN U-Net baseline) with the same neighbour-list interface.
#pragma once

#include <torch/nn/module.h>
#include <torch/nn/modules/container/sequential.h>
#include <torch/nn/pimpl.h>

#include "engine/model/neighbor_tensors.h"

namespace dynscope {

/// Sizes and variants of a GnnConv layer.
struct GnnConvOptions {
  GnnConvOptions(int64_t in_channels, int64_t out_channels)
      : in_channels_(in_channels), out_channels_(out_channels) {}
  TORCH_ARG(int64_t, in_channels);
  TORCH_ARG(int64_t, out_channels);
  /// Width of the edge and node MLPs (0: out_channels).
  TORCH_ARG(int64_t, hidden) = 0;
  /// Average messages over valid neighbours instead of summing them (relational layers).
  TORCH_ARG(bool, normalize) = false;
  /// Relative positions are divided by this length before the edge MLP.
  TORCH_ARG(double, position_scale) = 1.0;
};

/// Message passing as in DPI-Net (Li et al. 2019): messages m_k = φ_e([x_0; x_k; p_k − p_0]),
/// masked and summed (or averaged), then y_0 = φ_n([x_0; Σ m_k]). A query with no valid neighbour
/// outputs exactly zero (no message, no update; the residual around the layer keeps x_0).
/// Submodules "edge_mlp" and "node_mlp".
class GnnConvImpl : public torch::nn::Module {
 public:
  explicit GnnConvImpl(const GnnConvOptions& options);

  /// `query` `[M,3]`/`source` `[N,3]` float64, `source_features` `[N,C_in]`, `query_features`
  /// `[M,C_in]` (for resampling layers: the features of each query's nearest source point),
  /// `neighbors` `[M,K]` → `[M,C_out]`.
  torch::Tensor forward(const torch::Tensor& query, const torch::Tensor& source,
                        const torch::Tensor& source_features, const torch::Tensor& query_features,
                        const NeighborTensors& neighbors);

  const GnnConvOptions& options() const { return options_; }

  torch::nn::Sequential edge_mlp{nullptr};
  torch::nn::Sequential node_mlp{nullptr};

 private:
  // The unfused reference formulation (ConvImplementation::kUnfused).
  torch::Tensor forward_unfused(const torch::Tensor& query, const torch::Tensor& source,
                                const torch::Tensor& source_features,
                                const torch::Tensor& query_features,
                                const NeighborTensors& neighbors);

  GnnConvOptions options_;
};
TORCH_MODULE(GnnConv);

}  // namespace dynscope
