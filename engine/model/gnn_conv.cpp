// DPI-style message passing forward pass.
#include "engine/model/gnn_conv.h"

#include <torch/nn/modules/activation.h>
#include <torch/nn/modules/linear.h>

#include <string>

#include "engine/core/error.h"
#include "engine/model/conv_implementation.h"
#include "engine/model/fused_point_conv.h"

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

torch::Tensor GnnConvImpl::forward_unfused(const torch::Tensor& query, const torch::Tensor& source,
                                           const torch::Tensor& source_features,
                                           const torch::Tensor& query_features,
                                           const NeighborTensors& neighbors) {
  const int64_t m = neighbors.index.size(0), k = neighbors.index.size(1);
  const int64_t c = source_features.size(1);
  const torch::Tensor rel =
      ((gather_neighbors(source, neighbors.index) - query.unsqueeze(1)) / options_.position_scale())
          .to(torch::kFloat);
  const torch::Tensor xk = gather_neighbors(source_features, neighbors.index);
  const torch::Tensor x0 = query_features.unsqueeze(1).expand({m, k, c});
  torch::Tensor messages = edge_mlp->forward(torch::cat({x0, xk, rel}, -1)) *
                           neighbors.mask.unsqueeze(-1).to(torch::kFloat);
  if (neighbors.gate.defined()) messages = messages * neighbors.gate.unsqueeze(-1);
  torch::Tensor agg = messages.sum(1);
  const torch::Tensor count = neighbors.mask.sum(1).to(torch::kFloat);
  if (options_.normalize()) agg = agg / count.clamp_min(1.0).unsqueeze(1);
  const torch::Tensor y = node_mlp->forward(torch::cat({query_features, agg}, -1));
  return y * (count > 0).to(torch::kFloat).unsqueeze(1);
}

torch::Tensor GnnConvImpl::forward(const torch::Tensor& query, const torch::Tensor& source,
                                   const torch::Tensor& source_features,
                                   const torch::Tensor& query_features,
                                   const NeighborTensors& neighbors) {
  if (conv_implementation() == ConvImplementation::kUnfused) {
    return forward_unfused(query, source, source_features, query_features, neighbors);
  }
  const int64_t c = source_features.size(1);
  // φ_e's first layer on [x_0; x_k; p_k − p_0] splits into a per-query, a per-source and a
  // per-edge product; only the sum is formed per edge, by one fused gather.
  const auto edge_in = edge_mlp->ptr<torch::nn::LinearImpl>(0);
  const auto edge_out = edge_mlp->ptr<torch::nn::LinearImpl>(2);
  const torch::Tensor w = edge_in->weight;  // [hid, 2C+3]
  const torch::Tensor rel = neighbors.relative(query, source, options_.position_scale());
  const torch::Tensor pre =
      gather_add(torch::addmm(edge_in->bias, query_features, w.narrow(1, 0, c).t()),
                 torch::mm(source_features, w.narrow(1, c, c).t()),
                 torch::matmul(rel, w.narrow(1, 2 * c, 3).t()),
                 masked_index(neighbors));  // [M,K,hid]
  torch::Tensor messages =
      edge_out->forward(torch::relu(pre)).relu_() * neighbors.mask.unsqueeze(-1);
  if (neighbors.gate.defined()) messages = messages * neighbors.gate.unsqueeze(-1);
  torch::Tensor agg = messages.sum(1);
  if (options_.normalize()) agg = agg / neighbors.valid_count().clamp_min(1.0).unsqueeze(1);
  const torch::Tensor y = node_mlp->forward(torch::cat({query_features, agg}, -1));
  return y * neighbors.has_neighbors();
}

}  // namespace dynscope
