// A neighbour convolution wrapped PointConvFormer-style: 1×1 bottleneck in/out and a residual.
#pragma once

#include <torch/nn/module.h>
#include <torch/nn/modules/linear.h>
#include <torch/nn/modules/normalization.h>
#include <torch/nn/pimpl.h>

#include "engine/model/gnn_conv.h"
#include "engine/model/mesh_relational_conv.h"
#include "engine/model/neighbor_tensors.h"
#include "engine/model/point_conv.h"

namespace dynscope {

/// Which layer a ConvUnit wraps.
/// kMeshRelational wraps the three-layer interaction-point path (use forward_mesh).
enum class ConvKind { kPointConv, kGnn, kMeshRelational };

/// Sizes and variants of a ConvUnit.
struct ConvUnitOptions {
  ConvUnitOptions(int64_t in_channels, int64_t out_channels)
      : in_channels_(in_channels), out_channels_(out_channels) {}
  TORCH_ARG(int64_t, in_channels);
  TORCH_ARG(int64_t, out_channels);
  TORCH_ARG(ConvKind, conv) = ConvKind::kPointConv;
  TORCH_ARG(int64_t, c_mid) = 16;
  /// Positional embedding width of the PointConv (object convolutions; ignored by the GNN, whose
  /// edge MLP already sees p_k − p_0).
  TORCH_ARG(int64_t, pos_channels) = 0;
  /// Average over valid neighbours (relational convolutions).
  TORCH_ARG(bool, normalize) = false;
  /// LayerNorm after the reducing linear and after the convolution; false: no normalisation.
  TORCH_ARG(bool, layer_norm) = true;
  /// The convolution runs at max(1, out_channels / bottleneck_divisor) channels.
  TORCH_ARG(int64_t, bottleneck_divisor) = 4;
  TORCH_ARG(double, position_scale) = 1.0;
};

/// y = ReLU(s + expand(ReLU(norm(conv(ReLU(norm(reduce(x))))))). The shortcut s is x itself when
/// queries are the source points, or, when the convolution resamples (queries are another point
/// set), the features of each query's nearest source point (column 0 of its neighbour list);
/// a linear "shortcut" projection is added whenever in_channels != out_channels.
/// Submodules: "reduce", "reduce_norm", "conv", "conv_norm", "expand", "shortcut".
class ConvUnitImpl : public torch::nn::Module {
 public:
  /// A non-resampling unit reads a compacted list (NeighborTensors::compact) when its rows
  /// without neighbours times its input channels reach this: below, the dense unit costs less
  /// than the few more ops of the compacted one (256 rows of 32 channels, measured on the bundled
  /// Physion-like rollouts; a level-3 unit of 256 channels pays from 32 rows).
  static constexpr int64_t kMinIdleWork = 256 * 32;

  explicit ConvUnitImpl(const ConvUnitOptions& options);

  /// `x` `[N,C_in]` on `source` `[N,3]`; `query` `[M,3]`; `neighbors` `[M,K]` into source;
  /// `resample` false requires query == source (M == N). Returns `[M,C_out]`.
  torch::Tensor forward(const torch::Tensor& x, const torch::Tensor& source,
                        const torch::Tensor& query, const NeighborTensors& neighbors,
                        bool resample);

  /// Mesh relational unit: `x` `[V,C_in]` on `vertices` `[V,3]` → `[V,C_out]`; throws ValueError
  /// unless the unit was built with ConvKind::kMeshRelational.
  torch::Tensor forward_mesh(const torch::Tensor& x, const torch::Tensor& vertices,
                             const MeshTensors& mesh);

  const ConvUnitOptions& options() const { return options_; }
  int64_t bottleneck_channels() const { return mid_; }

  torch::nn::Linear reduce{nullptr};
  torch::nn::LayerNorm reduce_norm{nullptr};
  PointConv point_conv{nullptr};
  GnnConv gnn_conv{nullptr};
  MeshRelationalConv mesh_conv{nullptr};
  torch::nn::LayerNorm conv_norm{nullptr};
  torch::nn::Linear expand{nullptr};
  torch::nn::Linear shortcut{nullptr};

 private:
  torch::Tensor reduce_input(const torch::Tensor& x);
  /// expand(norm(conv_out)): the convolution's part of the output before the shortcut.
  torch::Tensor finish_conv(const torch::Tensor& conv_out);
  torch::Tensor finish(const torch::Tensor& conv_out, const torch::Tensor& shortcut_in);
  /// forward without resampling on a compacted list (NeighborTensors::compact).
  torch::Tensor forward_active(const torch::Tensor& x, const torch::Tensor& query,
                               const NeighborTensors& neighbors);

  ConvUnitOptions options_;
  int64_t mid_;
};
TORCH_MODULE(ConvUnit);

}  // namespace dynscope
