// Interaction PointConv U-Net (paper §3.4): input MLP, encoder, bottleneck, decoder, point head.
#pragma once

#include <torch/nn/module.h>
#include <torch/nn/modules/container/modulelist.h>
#include <torch/nn/modules/container/sequential.h>
#include <torch/nn/pimpl.h>

#include <string>
#include <vector>

#include "engine/model/interaction_block.h"
#include "engine/model/model_config.h"
#include "engine/model/neighbor_tensors.h"

namespace dynscope {

/// Features after one stage of a forward pass, for the debug trace and the viewer.
struct BlockRecord {
  std::string name;        ///< "input", "stem.i", "encoder.i", "bottleneck.i" or "decoder.i".
  int level = 0;           ///< Hierarchy level the features live on.
  torch::Tensor features;  ///< `[N_level,C]` float32, detached.
};

/// The U-Net. Channels at level l are config.channels(l). Encoder block i downsamples level i to
/// i+1 (object conv with level i+1's `down` list, residual from the kept point), bottleneck
/// blocks run at the coarsest level, decoder blocks upsample level l+1 to l (PointConv
/// interpolation at the stored level-l points with level l+1's `up` list, residual from the
/// nearest coarse point) and fuse the encoder features of level l (skip connection).
/// Submodules: "input_mlp", "stem", "encoder", "bottleneck", "decoder", "head".
class UNetImpl : public torch::nn::Module {
 public:
  /// Throws ValueError (from ModelConfig::validate) for an invalid configuration.
  UNetImpl(const ModelConfig& config, int64_t in_features, int64_t out_features = 3);

  /// `features` `[N_0,in_features]` float32 on level 0 of `hierarchy` → `[N_0,out_features]`.
  /// Appends one BlockRecord per stage to `record` when given. Throws ValueError if the
  /// hierarchy's level count or level-0 size does not match.
  torch::Tensor forward(const torch::Tensor& features, const HierarchyTensors& hierarchy,
                        std::vector<BlockRecord>* record = nullptr);

  const ModelConfig& config() const { return config_; }

  torch::nn::Sequential input_mlp{nullptr};
  torch::nn::ModuleList stem_list{nullptr};
  torch::nn::ModuleList encoder_list{nullptr};
  torch::nn::ModuleList bottleneck_list{nullptr};
  torch::nn::ModuleList decoder_list{nullptr};
  torch::nn::Sequential head{nullptr};

 private:
  InteractionBlock make_block(int64_t in, int64_t out, int64_t skip, int level) const;

  ModelConfig config_;
  std::vector<InteractionBlock> stem_, encoder_, bottleneck_, decoder_;
};
TORCH_MODULE(UNet);

}  // namespace dynscope
