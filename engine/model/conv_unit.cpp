// ConvUnit: bottleneck, convolution, residual.
#include "engine/model/conv_unit.h"

#include <torch/nn/functional/activation.h>

#include <algorithm>
#include <string>

#include "engine/core/error.h"
#include "engine/model/fused_point_conv.h"

namespace dynscope {

ConvUnitImpl::ConvUnitImpl(const ConvUnitOptions& options) : options_(options) {
  if (options.in_channels() < 1 || options.out_channels() < 1 || options.bottleneck_divisor() < 1) {
    throw ValueError("conv_unit", "invalid options: in " + std::to_string(options.in_channels()) +
                                      ", out " + std::to_string(options.out_channels()));
  }
  mid_ = std::max<int64_t>(1, options.out_channels() / options.bottleneck_divisor());
  reduce = register_module("reduce", torch::nn::Linear(options.in_channels(), mid_));
  if (options.layer_norm()) {
    reduce_norm =
        register_module("reduce_norm", torch::nn::LayerNorm(torch::nn::LayerNormOptions({mid_})));
  }
  if (options.conv() == ConvKind::kPointConv) {
    point_conv = register_module("conv", PointConv(PointConvOptions(mid_, mid_)
                                                       .c_mid(options.c_mid())
                                                       .pos_channels(options.pos_channels())
                                                       .normalize(options.normalize())
                                                       .position_scale(options.position_scale())));
  } else if (options.conv() == ConvKind::kGnn) {
    gnn_conv = register_module("conv", GnnConv(GnnConvOptions(mid_, mid_)
                                                   .normalize(options.normalize())
                                                   .position_scale(options.position_scale())));
  } else {
    mesh_conv =
        register_module("conv", MeshRelationalConv(MeshRelationalConvOptions(mid_, mid_)
                                                       .c_mid(options.c_mid())
                                                       .pos_channels(options.pos_channels())
                                                       .position_scale(options.position_scale())));
  }
  if (options.layer_norm()) {
    conv_norm =
        register_module("conv_norm", torch::nn::LayerNorm(torch::nn::LayerNormOptions({mid_})));
  }
  expand = register_module("expand", torch::nn::Linear(mid_, options.out_channels()));
  if (options.in_channels() != options.out_channels()) {
    shortcut = register_module(
        "shortcut",
        torch::nn::Linear(
            torch::nn::LinearOptions(options.in_channels(), options.out_channels()).bias(false)));
  }
}

torch::Tensor ConvUnitImpl::reduce_input(const torch::Tensor& x) {
  const torch::Tensor r = reduce->forward(x);
  if (!reduce_norm) return torch::relu(r);
  return layer_norm_relu(r, reduce_norm->weight, reduce_norm->bias, reduce_norm->options.eps());
}

torch::Tensor ConvUnitImpl::finish_conv(const torch::Tensor& conv_out) {
  const torch::Tensor c = conv_norm ? layer_norm_relu(conv_out, conv_norm->weight, conv_norm->bias,
                                                      conv_norm->options.eps())
                                    : torch::relu(conv_out);
  return expand->forward(c);
}

torch::Tensor ConvUnitImpl::finish(const torch::Tensor& conv_out,
                                   const torch::Tensor& shortcut_in) {
  torch::Tensor c = finish_conv(conv_out);
  const torch::Tensor s = shortcut ? shortcut->forward(shortcut_in) : shortcut_in;
  // In place: the sum and the ReLU overwrite a linear's output, which no backward reads.
  return c.add_(s).relu_();
}

torch::Tensor ConvUnitImpl::forward(const torch::Tensor& x, const torch::Tensor& source,
                                    const torch::Tensor& query, const NeighborTensors& neighbors,
                                    bool resample) {
  if (mesh_conv) throw ValueError("conv_unit", "a mesh relational unit needs forward_mesh");
  if (!resample && query.size(0) != source.size(0)) {
    throw ValueError("conv_unit", "a non-resampling unit needs the query points to be the source");
  }
  if (!resample && neighbors.active_list && !neighbors.gate.defined() &&
      (neighbors.rows() - neighbors.active.size(0)) * x.size(1) >= kMinIdleWork) {
    return forward_active(x, query, neighbors);
  }
  const torch::Tensor r = reduce_input(x);
  const torch::Tensor nearest = resample ? neighbors.nearest() : torch::Tensor();
  torch::Tensor c;
  if (point_conv) {
    c = point_conv->forward(query, source, r, neighbors);
  } else {
    const torch::Tensor r_query = resample ? r.index_select(0, nearest) : r;
    c = gnn_conv->forward(query, source, r, r_query, neighbors);
  }
  return finish(c, resample ? x.index_select(0, nearest) : x);
}

// A convolution is zero on a row without neighbours, so such a row's output is
// relu(x + e) with e = expand(norm(0)), the same e for every row: the reduction, convolution,
// norm and expansion run on the active rows only (a relational list leaves most rows without
// neighbours). Equal to the dense path up to the order of float sums.
torch::Tensor ConvUnitImpl::forward_active(const torch::Tensor& x, const torch::Tensor& query,
                                           const NeighborTensors& neighbors) {
  const torch::Tensor zero = torch::zeros({1, mid_}, x.options());
  const torch::Tensor idle = torch::relu((shortcut ? shortcut->forward(x) : x) + finish_conv(zero));
  if (neighbors.active.size(0) == 0) return idle;
  const NeighborTensors& list = *neighbors.active_list;
  const torch::Tensor xa = x.index_select(0, neighbors.active);
  const torch::Tensor qa = query.index_select(0, neighbors.active);
  const torch::Tensor r = reduce_input(xa);
  const torch::Tensor c =
      point_conv ? point_conv->forward(qa, qa, r, list) : gnn_conv->forward(qa, qa, r, r, list);
  return idle.index_copy(0, neighbors.active, finish(c, xa));
}

torch::Tensor ConvUnitImpl::forward_mesh(const torch::Tensor& x, const torch::Tensor& vertices,
                                         const MeshTensors& mesh) {
  if (!mesh_conv) throw ValueError("conv_unit", "forward_mesh needs a mesh relational unit");
  return finish(mesh_conv->forward(reduce_input(x), vertices, mesh), x);
}

}  // namespace dynscope
