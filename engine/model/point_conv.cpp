// Efficient PointConv forward pass.
#include "engine/model/point_conv.h"

#include <torch/autograd.h>
#include <torch/nn/modules/activation.h>

#include <string>

#include "engine/core/error.h"
#include "engine/model/conv_implementation.h"
#include "engine/model/fused_point_conv.h"

namespace dynscope {

PointConvImpl::PointConvImpl(const PointConvOptions& options) : options_(options) {
  if (options.in_channels() < 1 || options.out_channels() < 1 || options.c_mid() < 1 ||
      options.weight_hidden() < 1 || options.pos_channels() < 0 ||
      !(options.position_scale() > 0)) {
    throw ValueError("point_conv", "invalid options: in " + std::to_string(options.in_channels()) +
                                       ", out " + std::to_string(options.out_channels()) +
                                       ", c_mid " + std::to_string(options.c_mid()));
  }
  const int64_t hidden = options.weight_hidden();
  weightnet = register_module(
      "weightnet", torch::nn::Sequential(torch::nn::Linear(3, hidden), torch::nn::ReLU(),
                                         torch::nn::Linear(hidden, hidden), torch::nn::ReLU(),
                                         torch::nn::Linear(hidden, options.c_mid())));
  if (options.pos_channels() > 0) {
    const int64_t pe = options.pos_channels();
    pos_embed = register_module("pos_embed",
                                torch::nn::Sequential(torch::nn::Linear(3, pe), torch::nn::ReLU(),
                                                      torch::nn::Linear(pe, pe)));
  }
  const int64_t c_in = options.in_channels() + options.pos_channels();
  linear =
      register_module("linear", torch::nn::Linear(c_in * options.c_mid(), options.out_channels()));
}

torch::Tensor PointConvImpl::filter_weights(const torch::Tensor& query, const torch::Tensor& source,
                                            const NeighborTensors& neighbors) {
  const torch::Tensor rel = neighbors.relative(query, source, options_.position_scale());
  return weightnet->forward(rel) * neighbors.mask.unsqueeze(-1).to(torch::kFloat);
}

torch::Tensor PointConvImpl::forward_unfused(const torch::Tensor& query,
                                             const torch::Tensor& source,
                                             const torch::Tensor& features,
                                             const NeighborTensors& neighbors) {
  const int64_t m = neighbors.index.size(0);
  const torch::Tensor rel =
      ((gather_neighbors(source, neighbors.index) - query.unsqueeze(1)) / options_.position_scale())
          .to(torch::kFloat);
  torch::Tensor x = gather_neighbors(features, neighbors.index);  // [M,K,C_in]
  if (pos_embed) x = torch::cat({x, pos_embed->forward(rel)}, -1);
  torch::Tensor h =
      weightnet->forward(rel) * neighbors.mask.unsqueeze(-1).to(torch::kFloat);  // [M,K,c_mid]
  if (neighbors.gate.defined()) h = h * neighbors.gate.unsqueeze(-1);
  torch::Tensor agg = torch::matmul(h.transpose(1, 2), x);  // [M,c_mid,C]: Σ_k h_k x_kᵀ
  const torch::Tensor count = neighbors.mask.sum(1).to(torch::kFloat);
  if (options_.normalize()) agg = agg / count.clamp_min(1.0).view({m, 1, 1});
  const torch::Tensor y = linear->forward(agg.reshape({m, agg.size(1) * agg.size(2)}));
  return y * (count > 0).to(torch::kFloat).unsqueeze(1);
}

torch::Tensor PointConvImpl::forward(const torch::Tensor& query, const torch::Tensor& source,
                                     const torch::Tensor& features,
                                     const NeighborTensors& neighbors) {
  if (features.dim() != 2 || features.size(1) != options_.in_channels()) {
    throw ValueError("point_conv",
                     "expected features [N," + std::to_string(options_.in_channels()) + "], got " +
                         std::to_string(features.dim() == 2 ? features.size(1) : -1) + " channels");
  }
  if (conv_implementation() == ConvImplementation::kUnfused) {
    return forward_unfused(query, source, features, neighbors);
  }
  torch::Tensor product;  // W·agg, [M,C_out]
  if (features.scalar_type() == torch::kFloat &&
      conv_implementation() != ConvImplementation::kFusedComposed) {
    // The WeightNet and the embedding run per neighbour inside the aggregation (and again in its
    // backward): no [M,K,·] intermediate is written or saved; without gradients to record, the
    // linear runs inside it too. The MLPs' first layers take the position scale
    // (W·(r/s) = (W/s)·r), so the list's shared relative positions are read as they are, not
    // rescaled per convolution.
    const torch::Tensor rel = neighbors.relative(query, source, 1.0);
    if (rel.scalar_type() == torch::kFloat) {
      product =
          point_conv_aggregate_mlp_linear(features, rel, edge_mlps(1.0 / options_.position_scale()),
                                          neighbors.gate, masked_index(neighbors), linear->weight);
    }
  }
  if (!product.defined()) {
    product = torch::mm(
        aggregate_with_autograd(
            features, neighbors.relative(query, source, options_.position_scale()), neighbors),
        linear->weight.t());
  }
  // Without neighbours there is nothing to convolve: the bias must not leak into the output,
  // (W·agg + b)·has. The mean over the neighbours, (W·agg/n + b)·has = (W·agg)·(has/n) + has·b:
  // the scale goes on the [M,C_out] product instead of the [M,J·C'] aggregate.
  if (!options_.normalize()) return product.add_(linear->bias).mul_(neighbors.has_neighbors());
  return product.mul_(neighbors.inverse_count()).addcmul_(neighbors.has_neighbors(), linear->bias);
}

EdgeMlps PointConvImpl::edge_mlps(double position_factor) const {
  EdgeMlps m;
  auto layer = [](const torch::nn::Sequential& seq, size_t i) {
    return seq->ptr<torch::nn::LinearImpl>(i);
  };
  m.w1 = layer(weightnet, 0)->weight;
  m.b1 = layer(weightnet, 0)->bias;
  m.w2 = layer(weightnet, 2)->weight;
  m.b2 = layer(weightnet, 2)->bias;
  m.w3 = layer(weightnet, 4)->weight;
  m.b3 = layer(weightnet, 4)->bias;
  if (position_factor != 1.0) m.w1 = m.w1 * position_factor;
  if (pos_embed) {
    m.e1 = layer(pos_embed, 0)->weight;
    if (position_factor != 1.0) m.e1 = m.e1 * position_factor;
    m.c1 = layer(pos_embed, 0)->bias;
    m.e2 = layer(pos_embed, 2)->weight;
    m.c2 = layer(pos_embed, 2)->bias;
  }
  return m;
}

torch::Tensor PointConvImpl::aggregate_with_autograd(const torch::Tensor& features,
                                                     const torch::Tensor& rel,
                                                     const NeighborTensors& neighbors) {
  const torch::Tensor edge = pos_embed ? pos_embed->forward(rel) : torch::Tensor();
  // The fused op skips masked neighbours, so h needs no mask here.
  torch::Tensor h = weightnet->forward(rel);  // [M,K,c_mid]
  // The edge term h_k x_kᵀ is linear in h_k, so a gate scales the whole message of edge k.
  if (neighbors.gate.defined()) h = h * neighbors.gate.unsqueeze(-1);
  return point_conv_aggregate(features, edge, h, masked_index(neighbors));  // [M,c_mid·C]
}

}  // namespace dynscope
