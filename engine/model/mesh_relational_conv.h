// Relational PointConv for meshes (paper §3.2): vertices → sender interaction points → receiver
// interaction points → vertices, three PointConv layers.
#pragma once

#include <torch/nn/module.h>
#include <torch/nn/pimpl.h>

#include "engine/model/neighbor_tensors.h"
#include "engine/model/point_conv.h"

namespace dynscope {

/// Sizes of a MeshRelationalConv.
struct MeshRelationalConvOptions {
  MeshRelationalConvOptions(int64_t in_channels, int64_t out_channels)
      : in_channels_(in_channels), out_channels_(out_channels) {}
  TORCH_ARG(int64_t, in_channels);
  TORCH_ARG(int64_t, out_channels);
  TORCH_ARG(int64_t, c_mid) = 16;
  /// Positional embedding width of the first and third layers.
  TORCH_ARG(int64_t, pos_channels) = 8;
  TORCH_ARG(double, position_scale) = 1.0;
};

/// Layer 1 "to_sender": features at each interaction point from its face's 3 vertices (sum, with
/// positional embedding). Layer 2 "to_receiver": each interaction point as receiver averages the
/// sender points on the faces paired with its face. Layer 3 "to_vertex": each vertex averages the
/// receiver points on the faces that contain it (with positional embedding); vertices touching no
/// interaction point output exactly zero. ReLU between layers.
class MeshRelationalConvImpl : public torch::nn::Module {
 public:
  explicit MeshRelationalConvImpl(const MeshRelationalConvOptions& options);

  /// `x` `[V,C_in]` on `vertices` `[V,3]` float64 → `[V,C_out]`.
  torch::Tensor forward(const torch::Tensor& x, const torch::Tensor& vertices,
                        const MeshTensors& mesh);

  PointConv to_sender{nullptr};
  PointConv to_receiver{nullptr};
  PointConv to_vertex{nullptr};
};
TORCH_MODULE(MeshRelationalConv);

}  // namespace dynscope
