// ConvUnit: residual paths for same-set and resampling convolutions.
#include "engine/model/conv_unit.h"

#include <gtest/gtest.h>
#include <torch/types.h>
#include <torch/utils.h>

#include "engine/core/error.h"

namespace dynscope {
namespace {

TEST(ConvUnitTest, ResamplingResidualUsesNearestSourcePoint) {
  torch::NoGradGuard no_grad;
  torch::manual_seed(1);
  ConvUnit unit(ConvUnitOptions(6, 6).c_mid(4).pos_channels(2));
  // With the expanding linear zeroed the unit is ReLU(shortcut) exactly.
  unit->expand->weight.zero_();
  unit->expand->bias.zero_();
  const torch::Tensor source = torch::rand({10, 3}, torch::kFloat64);
  const torch::Tensor query = source.index_select(0, torch::tensor({7, 2, 4}));
  const torch::Tensor x = torch::randn({10, 6});
  NeighborTensors nb;
  nb.index = torch::tensor({{7, 1, 3}, {2, 5, -1}, {4, 0, 9}});
  nb.mask = nb.index >= 0;
  const torch::Tensor y = unit->forward(x, source, query, nb, true);
  EXPECT_TRUE(torch::allclose(y, torch::relu(x.index_select(0, torch::tensor({7, 2, 4})))));
}

TEST(ConvUnitTest, ChannelChangeAddsShortcutProjection) {
  ConvUnit same(ConvUnitOptions(8, 8));
  ConvUnit wider(ConvUnitOptions(8, 16).conv(ConvKind::kGnn));
  EXPECT_FALSE(same->shortcut);
  ASSERT_TRUE(wider->shortcut);
  EXPECT_EQ(wider->bottleneck_channels(), 4);
  const torch::Tensor pos = torch::rand({5, 3}, torch::kFloat64);
  NeighborTensors nb;
  nb.index = torch::tensor({{0, 1}, {1, 2}, {2, 3}, {3, 4}, {4, 0}});
  nb.mask = nb.index >= 0;
  const torch::Tensor y = wider->forward(torch::randn({5, 8}), pos, pos, nb, false);
  EXPECT_EQ(y.sizes(), (std::vector<int64_t>{5, 16}));
  EXPECT_GE(y.min().item<float>(), 0.0f);
}

TEST(ConvUnitTest, NonResamplingUnitNeedsSameQueryPoints) {
  ConvUnit unit(ConvUnitOptions(4, 4));
  NeighborTensors nb;
  nb.index = torch::zeros({3, 2}, torch::kInt64);
  nb.mask = nb.index >= 0;
  EXPECT_THROW(unit->forward(torch::randn({5, 4}), torch::rand({5, 3}, torch::kFloat64),
                             torch::rand({3, 3}, torch::kFloat64), nb, false),
               ValueError);
}

}  // namespace
}  // namespace dynscope
