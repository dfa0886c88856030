// InteractionBlock forward pass.
#include "engine/model/interaction_block.h"

#include <torch/nn/functional/activation.h>

#include "engine/core/error.h"

namespace dynscope {

InteractionBlockImpl::InteractionBlockImpl(const InteractionBlockOptions& options)
    : options_(options) {
  const ConvKind conv = options.kind() == ModelKind::kGnn ? ConvKind::kGnn : ConvKind::kPointConv;
  auto unit = [&](int64_t in, bool normalize, int64_t pos, ConvKind kind) {
    return ConvUnitOptions(in, options.out_channels())
        .conv(kind)
        .c_mid(options.c_mid())
        .pos_channels(pos)
        .normalize(normalize)
        .layer_norm(options.layer_norm())
        .bottleneck_divisor(options.bottleneck_divisor())
        .position_scale(options.position_scale());
  };
  object = register_module(
      "object", ConvUnit(unit(options.in_channels(), false, options.pos_channels(), conv)));
  if (options.skip_channels() > 0) {
    fuse =
        register_module("fuse", torch::nn::Linear(options.out_channels() + options.skip_channels(),
                                                  options.out_channels()));
  }
  if (options.relational() && options.kind() != ModelKind::kFlat) {
    relational = register_module(
        "relational",
        ConvUnit(options.mesh_relational() ? unit(options.out_channels(), true,
                                                  options.pos_channels(), ConvKind::kMeshRelational)
                                           : unit(options.out_channels(), true, 0, conv)));
  }
}

torch::Tensor InteractionBlockImpl::forward(const torch::Tensor& x, const torch::Tensor& source,
                                            const LevelTensors& query,
                                            const NeighborTensors& object_neighbors, bool resample,
                                            const torch::Tensor& skip) {
  torch::Tensor y = object->forward(x, source, query.points, object_neighbors, resample);
  if (fuse) {
    if (!skip.defined()) throw ValueError("interaction_block", "this block needs skip features");
    y = torch::relu(fuse->forward(torch::cat({y, skip}, -1)));
  }
  if (relational && options_.mesh_relational()) {
    if (!query.has_mesh) throw ValueError("interaction_block", "mesh relational unit without mesh");
    y = relational->forward_mesh(y, query.points, query.mesh);
  } else if (relational) {
    y = relational->forward(y, query.points, query.points, query.relational, false);
  }
  return y;
}

}  // namespace dynscope
