// DPI-style message passing forward pass.
#include "engine/model/gnn_conv.h"

#include <torch/nn/modules/activation.h>
#include <torch/nn/modules/linear.h>

#include <string>

#include "engine/core/error.h"

namespace dynscope {

GnnConvImpl::GnnConvImpl(const GnnConvOptions& options) : options_(options) {
  if (options.in_channels() < 1 || options.out_channels() < 1 || options.hidden() < 0 ||
      !(options.position_scale() > 0)) {
    throw ValueError("gnn_conv", "invalid options: in " + std::to_string(options.in_channels()) +
                                     ", out " + std::to_string(options.out_channels()));
  }
  const int64_t c = options.in_channels();
  const int64_t hid = options.hidden() > 0 ? options.hidden() : options.out_channels();
  edge_mlp = register_module(
      "edge_mlp", torch::nn::Sequential(torch::nn::Linear(2 * c + 3, hid), torch::nn::ReLU(),
                                        torch::nn::Linear(hid, hid), torch::nn::ReLU()));
  node_mlp = register_module(
      "node_mlp", torch::nn::Sequential(torch::nn::Linear(c + hid, hid), torch::nn::ReLU(),
                                        torch::nn::Linear(hid, options.out_channels())));
}

torch::Tensor GnnConvImpl::forward(const torch::Tensor& query, const torch::Tensor& source,
                                   const torch::Tensor& source_features,
                                   const torch::Tensor& query_features,
                                   const NeighborTensors& neighbors) {
  const int64_t m = neighbors.index.size(0), k = neighbors.index.size(1);
  const int64_t c = source_features.size(1);
  const torch::Tensor rel =
      relative_positions(query, source, neighbors.index, options_.position_scale());
  const torch::Tensor xk = gather_neighbors(source_features, neighbors.index);
  const torch::Tensor x0 = query_features.unsqueeze(1).expand({m, k, c});
  const torch::Tensor messages = edge_mlp->forward(torch::cat({x0, xk, rel}, -1)) *
                                 neighbors.mask.unsqueeze(-1).to(torch::kFloat);
  torch::Tensor agg = messages.sum(1);
  const torch::Tensor count = neighbors.valid_count();
  if (options_.normalize()) agg = agg / count.clamp_min(1.0).unsqueeze(1);
  const torch::Tensor y = node_mlp->forward(torch::cat({query_features, agg}, -1));
  return y * (count > 0).to(torch::kFloat).unsqueeze(1);
}

}  // namespace dynscope
