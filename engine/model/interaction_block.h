// Interaction block (paper §3.3): Object conv (may resample) then Relational conv, with an
// optional U-Net skip connection fused in between.
#pragma once

#include <torch/nn/module.h>
#include <torch/nn/modules/linear.h>
#include <torch/nn/pimpl.h>

#include "engine/model/conv_unit.h"
#include "engine/model/model_config.h"
#include "engine/model/neighbor_tensors.h"

namespace dynscope {

/// Sizes and variants of an InteractionBlock.
struct InteractionBlockOptions {
  InteractionBlockOptions(int64_t in_channels, int64_t out_channels)
      : in_channels_(in_channels), out_channels_(out_channels) {}
  TORCH_ARG(int64_t, in_channels);
  TORCH_ARG(int64_t, out_channels);
  /// kPointConv / kGnn pick the layer; kFlat uses PointConv without a relational unit.
  TORCH_ARG(ModelKind, kind) = ModelKind::kPointConv;
  /// Channels of the skip features fused after the object unit (0: no skip connection).
  TORCH_ARG(int64_t, skip_channels) = 0;
  /// Whether the block has a relational unit (false for the flat baseline).
  TORCH_ARG(bool, relational) = true;
  /// The relational unit is the mesh interaction-point path (query level must carry a mesh).
  TORCH_ARG(bool, mesh_relational) = false;
  TORCH_ARG(int64_t, c_mid) = 16;
  TORCH_ARG(int64_t, pos_channels) = 8;
  TORCH_ARG(bool, layer_norm) = true;
  TORCH_ARG(int64_t, bottleneck_divisor) = 4;
  /// Relative positions in every conv of the block are divided by this (the level's radius).
  TORCH_ARG(double, position_scale) = 1.0;
};

/// Object unit (same-object neighbours, positional embedding, sum) from the source points to the
/// query level, then, if a skip is given, ReLU(fuse([y; skip])), then the relational unit
/// (other-object neighbours within the radius, averaged) at the query level.
/// Submodules: "object", "fuse" (with skip), "relational" (unless disabled).
class InteractionBlockImpl : public torch::nn::Module {
 public:
  explicit InteractionBlockImpl(const InteractionBlockOptions& options);

  /// `x` `[N,C_in]` on `source` `[N,3]`; `query` is the output level (its points and relational
  /// list); `object_neighbors` index source for each query point; `resample` says whether the
  /// query points differ from the source points; `skip` `[M,skip_channels]` or undefined.
  /// Returns `[M,C_out]`.
  torch::Tensor forward(const torch::Tensor& x, const torch::Tensor& source,
                        const LevelTensors& query, const NeighborTensors& object_neighbors,
                        bool resample, const torch::Tensor& skip = {});

  const InteractionBlockOptions& options() const { return options_; }

  ConvUnit object{nullptr};
  torch::nn::Linear fuse{nullptr};
  ConvUnit relational{nullptr};

 private:
  InteractionBlockOptions options_;
};
TORCH_MODULE(InteractionBlock);

}  // namespace dynscope
