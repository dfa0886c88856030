// UNet construction and forward pass.
#include "engine/model/unet.h"

#include <torch/nn/modules/activation.h>
#include <torch/nn/modules/linear.h>

#include <string>

#include "engine/core/error.h"

namespace dynscope {

InteractionBlock UNetImpl::make_block(int64_t in, int64_t out, int64_t skip, int level) const {
  return InteractionBlock(InteractionBlockOptions(in, out)
                              .kind(config_.kind)
                              .skip_channels(skip)
                              .relational(config_.has_relational(level))
                              .mesh_relational(config_.input == InputMode::kMesh && level == 0)
                              .c_mid(config_.c_mid)
                              .pos_channels(config_.pos_channels)
                              .layer_norm(config_.layer_norm)
                              .bottleneck_divisor(config_.bottleneck_divisor)
                              .position_scale(config_.radius_at(level)));
}

UNetImpl::UNetImpl(const ModelConfig& config, int64_t in_features, int64_t out_features)
    : config_(config) {
  config.validate();
  if (in_features < 1 || out_features < 1) {
    throw ValueError("unet", "in_features and out_features must be >= 1");
  }
  const int levels = config.levels;
  const int64_t c0 = config.channels(0);
  input_mlp = register_module(
      "input_mlp", torch::nn::Sequential(torch::nn::Linear(in_features, c0), torch::nn::ReLU(),
                                         torch::nn::Linear(c0, c0), torch::nn::ReLU()));
  stem_list = register_module("stem", torch::nn::ModuleList());
  encoder_list = register_module("encoder", torch::nn::ModuleList());
  bottleneck_list = register_module("bottleneck", torch::nn::ModuleList());
  decoder_list = register_module("decoder", torch::nn::ModuleList());
  for (int i = 0; i < config.stem_blocks; ++i) {
    stem_.push_back(make_block(c0, c0, 0, 0));
    stem_list->push_back(stem_.back());
  }
  for (int l = 0; l + 1 < levels; ++l) {
    encoder_.push_back(make_block(config.channels(l), config.channels(l + 1), 0, l + 1));
    encoder_list->push_back(encoder_.back());
  }
  const int64_t cb = config.channels(levels - 1);
  for (int i = 0; i < config.bottleneck_blocks; ++i) {
    bottleneck_.push_back(make_block(cb, cb, 0, levels - 1));
    bottleneck_list->push_back(bottleneck_.back());
  }
  for (int l = levels - 2; l >= 0; --l) {
    decoder_.push_back(
        make_block(config.channels(l + 1), config.channels(l), config.channels(l), l));
    decoder_list->push_back(decoder_.back());
  }
  head = register_module("head", torch::nn::Sequential(torch::nn::Linear(c0, c0), torch::nn::ReLU(),
                                                       torch::nn::Linear(c0, out_features)));
}

torch::Tensor UNetImpl::forward(const torch::Tensor& features, const HierarchyTensors& hierarchy,
                                std::vector<BlockRecord>* record) {
  const int levels = config_.levels;
  if (hierarchy.num_levels() != levels) {
    throw ValueError("hierarchy", "has " + std::to_string(hierarchy.num_levels()) +
                                      " levels, the model expects " + std::to_string(levels));
  }
  const auto& lv = hierarchy.levels;
  if (lv[0].points.size(0) != features.size(0)) {
    throw ValueError("hierarchy", "level 0 has " + std::to_string(lv[0].points.size(0)) +
                                      " points but there are " + std::to_string(features.size(0)) +
                                      " feature rows");
  }
  auto note = [&](const std::string& name, int level, const torch::Tensor& x) {
    if (record) record->push_back({name, level, x.detach()});
  };

  torch::Tensor x = input_mlp->forward(features);
  note("input", 0, x);
  for (size_t i = 0; i < stem_.size(); ++i) {
    x = stem_[i]->forward(x, lv[0].points, lv[0], lv[0].same, false);
    note("stem." + std::to_string(i), 0, x);
  }
  std::vector<torch::Tensor> skips{x};
  for (int l = 0; l + 1 < levels; ++l) {
    const LevelTensors& q = lv[static_cast<size_t>(l + 1)];
    x = encoder_[static_cast<size_t>(l)]->forward(x, lv[static_cast<size_t>(l)].points, q, q.down,
                                                  true);
    note("encoder." + std::to_string(l), l + 1, x);
    skips.push_back(x);
  }
  const LevelTensors& coarsest = lv[static_cast<size_t>(levels - 1)];
  for (size_t i = 0; i < bottleneck_.size(); ++i) {
    x = bottleneck_[i]->forward(x, coarsest.points, coarsest, coarsest.same, false);
    note("bottleneck." + std::to_string(i), levels - 1, x);
  }
  for (int l = levels - 2, j = 0; l >= 0; --l, ++j) {
    const LevelTensors& src = lv[static_cast<size_t>(l + 1)];
    x = decoder_[static_cast<size_t>(j)]->forward(x, src.points, lv[static_cast<size_t>(l)], src.up,
                                                  true, skips[static_cast<size_t>(l)]);
    note("decoder." + std::to_string(j), l, x);
  }
  return head->forward(x);
}

}  // namespace dynscope
