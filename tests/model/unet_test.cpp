// UNet: level sizes and feature shapes, gradients of every parameter, all three model kinds.
#include "engine/model/unet.h"

#include <gtest/gtest.h>
#include <torch/types.h>
#include <torch/utils.h>

#include "engine/core/error.h"
#include "engine/model/hierarchy.h"
#include "tests/model/model_test_util.h"

namespace dynscope {
namespace {

using testing::make_scene;
using testing::tiny_config;

HierarchyTensors hierarchy_for(const ModelConfig& c, const testing::TestScene& scene) {
  return to_tensors(build_hierarchy(scene.points, scene.ids, HierarchyOptions::from_config(c)));
}

TEST(UNetTest, StageFeaturesLiveOnTheRightLevelWithTheRightWidth) {
  torch::NoGradGuard no_grad;
  ModelConfig c = tiny_config();
  c.stem_blocks = 1;
  const auto scene = make_scene(3, 80, 1);
  const HierarchyTensors h = hierarchy_for(c, scene);
  UNet net(c, 7, 3);
  std::vector<BlockRecord> record;
  const torch::Tensor out = net->forward(torch::randn({240, 7}), h, &record);
  EXPECT_EQ(out.sizes(), (std::vector<int64_t>{240, 3}));
  // input, stem, 2 encoder, 1 bottleneck, 2 decoder stages.
  ASSERT_EQ(record.size(), 7u);
  const std::vector<std::pair<std::string, int>> expected{
      {"input", 0},        {"stem.0", 0},    {"encoder.0", 1}, {"encoder.1", 2},
      {"bottleneck.0", 2}, {"decoder.0", 1}, {"decoder.1", 0}};
  for (size_t i = 0; i < record.size(); ++i) {
    EXPECT_EQ(record[i].name, expected[i].first);
    EXPECT_EQ(record[i].level, expected[i].second);
    EXPECT_EQ(record[i].features.size(0), h.levels[record[i].level].points.size(0));
    EXPECT_EQ(record[i].features.size(1), c.channels(record[i].level)) << record[i].name;
  }
}

void expect_all_gradients(ModelKind kind) {
  const ModelConfig c = tiny_config(kind);
  const auto scene = make_scene(3, 70, 2);
  const HierarchyTensors h = hierarchy_for(c, scene);
  torch::manual_seed(3);
  UNet net(c, 7, 3);
  net->forward(torch::randn({210, 7}), h).square().sum().backward();
  int zero = 0, total = 0;
  for (const auto& p : net->named_parameters()) {
    const torch::Tensor g = p.value().grad();
    ASSERT_TRUE(g.defined()) << to_string(kind) << " " << p.key();
    EXPECT_TRUE(torch::isfinite(g).all().item<bool>()) << p.key();
    zero += g.abs().sum().item<double>() == 0.0;
    ++total;
  }
  EXPECT_EQ(zero, 0) << to_string(kind) << ": " << zero << " of " << total
                     << " parameters got an all-zero gradient";
}

TEST(UNetTest, EveryParameterGetsAFiniteGradientPointConv) {
  expect_all_gradients(ModelKind::kPointConv);
}
TEST(UNetTest, EveryParameterGetsAFiniteGradientGnn) { expect_all_gradients(ModelKind::kGnn); }
TEST(UNetTest, EveryParameterGetsAFiniteGradientFlat) { expect_all_gradients(ModelKind::kFlat); }

TEST(UNetTest, SingleLevelAndConstantWidthWork) {
  ModelConfig c = tiny_config();
  c.levels = 1;
  c.width_growth = 1.0;
  c.bottleneck_blocks = 2;
  const auto scene = make_scene(2, 40, 4);
  UNet net(c, 7, 3);
  EXPECT_EQ(net->forward(torch::randn({80, 7}), hierarchy_for(c, scene)).sizes(),
            (std::vector<int64_t>{80, 3}));
}

TEST(UNetTest, RejectsHierarchyOfAnotherShape) {
  const ModelConfig c = tiny_config();
  ModelConfig other = c;
  other.levels = 2;
  const auto scene = make_scene(2, 40, 5);
  UNet net(c, 7, 3);
  EXPECT_THROW(net->forward(torch::randn({80, 7}), hierarchy_for(other, scene)), ValueError);
  EXPECT_THROW(net->forward(torch::randn({79, 7}), hierarchy_for(c, scene)), ValueError);
}

TEST(UNetTest, CheckpointKeysAreStable) {
  const ModelConfig c = tiny_config();
  UNet net(c, 7, 3);
  const auto params = net->named_parameters();
  EXPECT_TRUE(params.contains("encoder.0.object.conv.weightnet.0.weight"));
  EXPECT_TRUE(params.contains("encoder.0.relational.conv.linear.weight"));
  EXPECT_TRUE(params.contains("decoder.1.fuse.weight"));
  EXPECT_TRUE(params.contains("bottleneck.0.object.reduce_norm.weight"));
  EXPECT_TRUE(params.contains("head.2.bias"));
}

// The paper's U-Net for meshes relates objects at level 0 only: the blocks at coarser levels have
// no relational unit, the rest of the network is unchanged, and every parameter still learns.
TEST(UNetTest, RelationalTopOnlyLeavesCoarseLevelsWithoutRelationalUnits) {
  ModelConfig c = tiny_config();
  c.stem_blocks = 1;
  c.relational_top_only = true;
  const auto scene = make_scene(3, 70, 6);
  const HierarchyTensors h = hierarchy_for(c, scene);
  torch::manual_seed(4);
  UNet net(c, 7, 3);
  const auto params = net->named_parameters();
  EXPECT_TRUE(params.contains("stem.0.relational.conv.linear.weight"));
  EXPECT_TRUE(params.contains("decoder.1.relational.conv.linear.weight"));  // level 0
  for (const char* block : {"encoder.0", "encoder.1", "bottleneck.0", "decoder.0"}) {
    EXPECT_TRUE(params.contains(std::string(block) + ".object.conv.linear.weight")) << block;
    EXPECT_FALSE(params.contains(std::string(block) + ".relational.conv.linear.weight")) << block;
  }
  ModelConfig all = c;
  all.relational_top_only = false;
  EXPECT_LT(params.size(), UNet(all, 7, 3)->named_parameters().size());
  net->forward(torch::randn({210, 7}), h).square().sum().backward();
  for (const auto& p : net->named_parameters()) {
    ASSERT_TRUE(p.value().grad().defined()) << p.key();
    EXPECT_GT(p.value().grad().abs().sum().item<double>(), 0.0) << p.key();
  }
}

}  // namespace
}  // namespace dynscope

namespace dynscope {
namespace {

// Every list of a hierarchy converted in one pass (prepared_tensors, what to_tensors uses) holds
// what converting it and then calling prepare() on its points computes with LibTorch ops: the
// same index (−1 where masked), mask, relative positions, counts and scales, exactly.
TEST(UNetTest, ListsConvertedInOnePassEqualConvertingThenPreparing) {
  ModelConfig c = testing::tiny_config();
  const auto scene = testing::make_scene(3, 80, 4);
  const Hierarchy h = build_hierarchy(scene.points, scene.ids, HierarchyOptions::from_config(c));
  const HierarchyTensors fast = to_tensors(h);
  auto expect_same = [](const NeighborTensors& a, const NeighborTensors& b,
                        const std::string& what) {
    EXPECT_TRUE(torch::equal(a.index, b.index)) << what;
    EXPECT_TRUE(torch::equal(a.mask, b.mask)) << what;
    EXPECT_TRUE(torch::equal(a.rel, b.rel)) << what;
    EXPECT_TRUE(torch::equal(a.count, b.count)) << what;
    EXPECT_TRUE(torch::equal(a.has_any, b.has_any)) << what;
    EXPECT_TRUE(torch::equal(a.inverse_count(), b.inverse_count())) << what;
  };
  int masked = 0;
  for (int l = 0; l < h.num_levels(); ++l) {
    const HierarchyLevel& level = h.levels[static_cast<size_t>(l)];
    const torch::Tensor points = points_to_tensor(level.points);
    NeighborTensors same = to_tensors(level.same);
    same.prepare(points, points);
    expect_same(fast.levels[static_cast<size_t>(l)].same, same, std::to_string(l) + "/same");
    NeighborTensors relational = to_tensors(level.relational);
    relational.prepare(points, points);
    expect_same(fast.levels[static_cast<size_t>(l)].relational, relational,
                std::to_string(l) + "/relational");
    masked += static_cast<int>((level.relational.mask.array() == 0).count());
    if (l == 0) continue;
    const torch::Tensor finer = points_to_tensor(h.levels[static_cast<size_t>(l - 1)].points);
    NeighborTensors down = to_tensors(level.down), up = to_tensors(level.up);
    down.prepare(points, finer);
    up.prepare(finer, points);
    expect_same(fast.levels[static_cast<size_t>(l)].down, down, std::to_string(l) + "/down");
    expect_same(fast.levels[static_cast<size_t>(l)].up, up, std::to_string(l) + "/up");
  }
  EXPECT_GT(masked, 0);  // the relational lists have masked entries to get right
  // A valid entry outside the source points is an error, not a read out of bounds.
  NeighborList bad = h.levels[0].same;
  bad.index(0, 0) = static_cast<int32_t>(h.levels[0].points.rows());
  EXPECT_THROW(prepared_tensors(bad, h.levels[0].points, h.levels[0].points), ValueError);
}

}  // namespace
}  // namespace dynscope
