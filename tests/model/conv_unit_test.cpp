// ConvUnit: residual paths for same-set and resampling convolutions; relational lists compacted
// to their rows with neighbours.
#include "engine/model/conv_unit.h"

#include <gtest/gtest.h>
#include <torch/autograd.h>
#include <torch/types.h>
#include <torch/utils.h>

#include <algorithm>
#include <memory>
#include <utility>
#include <vector>

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

// A relational list by brute force: for each of `n` random points (object id i mod 3), the other
// objects' points within `radius`, nearest first, at most k; prepared on the points.
NeighborTensors relational_case(int64_t n, double radius, int64_t k, uint64_t seed,
                                torch::Tensor* points) {
  torch::manual_seed(seed);
  *points = torch::rand({n, 3}, torch::kFloat64);
  const auto p = points->accessor<double, 2>();
  torch::Tensor index = torch::full({n, k}, -1, torch::kInt64);
  for (int64_t i = 0; i < n; ++i) {
    std::vector<std::pair<double, int64_t>> near;
    for (int64_t j = 0; j < n; ++j) {
      if (j % 3 == i % 3) continue;
      double d = 0;
      for (int c = 0; c < 3; ++c) d += (p[i][c] - p[j][c]) * (p[i][c] - p[j][c]);
      if (d <= radius * radius) near.emplace_back(d, j);
    }
    std::sort(near.begin(), near.end());
    for (int64_t t = 0; t < std::min<int64_t>(k, static_cast<int64_t>(near.size())); ++t) {
      index[i][t] = near[static_cast<size_t>(t)].second;
    }
  }
  NeighborTensors nb;
  nb.index = index;
  nb.mask = index >= 0;
  nb.prepare(*points, *points);
  return nb;
}

// The compacted path (the active rows alone, relu(x + e) for the others) against the dense one,
// for PointConv and GNN units with and without LayerNorm: outputs and the gradients of the
// input and of every parameter; lists with no row active and with every row active. 300 rows of
// 64 channels leave enough rows without neighbours for the unit to take the compacted list
// (ConvUnit::kMinIdleWork); that it does is shown by spoiling the compacted list's positions.
TEST(ConvUnitTest, ACompactedRelationalListGivesTheDenseOutputAndGradients) {
  const int64_t n = 300, channels = 64;
  for (double radius : {0.08, 0.0, 5.0}) {
    torch::Tensor points;
    const NeighborTensors dense = relational_case(n, radius, 5, 3, &points);
    NeighborTensors compacted = dense;
    compacted.compact(1);
    const int64_t active = (dense.count > 0).sum().item<int64_t>();
    if (radius == 5.0) {  // every row has neighbours: nothing to compact
      EXPECT_EQ(active, n);
      EXPECT_FALSE(compacted.active_list);
      continue;
    }
    ASSERT_TRUE(compacted.active_list) << "radius " << radius;
    EXPECT_EQ(compacted.active.size(0), active);
    if (radius > 0) {
      EXPECT_GT(active, 20);
      EXPECT_GE((n - active) * channels, ConvUnitImpl::kMinIdleWork);
    }
    for (ConvKind kind : {ConvKind::kPointConv, ConvKind::kGnn}) {
      for (bool norm : {true, false}) {
        torch::manual_seed(7);
        ConvUnit unit(ConvUnitOptions(channels, channels)
                          .conv(kind)
                          .c_mid(4)
                          .normalize(true)
                          .layer_norm(norm)
                          .position_scale(0.08));
        const torch::Tensor x = torch::randn({n, channels}).requires_grad_(true);
        const torch::Tensor ref = unit->forward(x, points, points, dense, false);
        const torch::Tensor got = unit->forward(x, points, points, compacted, false);
        ASSERT_EQ(got.sizes(), ref.sizes());
        EXPECT_TRUE(torch::allclose(got, ref, 1e-5, 1e-6)) << (got - ref).abs().max();
        if (active > 0) {
          NeighborTensors spoiled = compacted;
          auto list = std::make_shared<NeighborTensors>(*compacted.active_list);
          list->rel = torch::ones_like(list->rel);
          spoiled.active_list = list;
          const torch::Tensor read = unit->forward(x, points, points, spoiled, false);
          EXPECT_FALSE(torch::allclose(read, ref, 1e-3, 1e-3)) << "the compacted list was not read";
          // Eight channels: too few rows without neighbours to pay; the unit stays dense.
          ConvUnit narrow(ConvUnitOptions(8, 8).conv(kind).c_mid(4).normalize(true));
          const torch::Tensor x8 = torch::randn({n, 8});
          EXPECT_TRUE(torch::equal(narrow->forward(x8, points, points, spoiled, false),
                                   narrow->forward(x8, points, points, dense, false)));
        }
        std::vector<torch::Tensor> wrt = unit->parameters();
        wrt.push_back(x);
        const torch::Tensor w = torch::randn_like(ref);
        const auto gr = torch::autograd::grad({(ref * w).sum()}, wrt, {}, true, false, true);
        const auto gg = torch::autograd::grad({(got * w).sum()}, wrt, {}, true, false, true);
        for (size_t i = 0; i < wrt.size(); ++i) {
          const torch::Tensor a = gr[i].defined() ? gr[i] : torch::zeros_like(wrt[i]);
          const torch::Tensor b = gg[i].defined() ? gg[i] : torch::zeros_like(wrt[i]);
          EXPECT_TRUE(torch::allclose(a, b, 1e-5, 1e-5))
              << "radius " << radius << " kind " << static_cast<int>(kind) << " norm " << norm
              << " gradient " << i << ": " << (a - b).abs().max();
        }
      }
    }
  }
}

// compact() leaves a list whose rows read a source without neighbours of its own (not a
// relational list) as it is, and one with fewer rows without neighbours than asked for.
TEST(ConvUnitTest, AListReadingRowsWithoutNeighboursIsNotCompacted) {
  const torch::Tensor points = torch::rand({4, 3}, torch::kFloat64);
  NeighborTensors nb;
  nb.index = torch::tensor({{1, -1}, {2, -1}, {-1, -1}, {-1, -1}});  // row 1 reads row 2
  nb.mask = nb.index >= 0;
  nb.prepare(points, points);
  nb.compact(1);
  EXPECT_FALSE(nb.active_list);
  EXPECT_FALSE(nb.active.defined());
  nb.index = torch::tensor({{1, -1}, {0, -1}, {-1, -1}, {-1, -1}});
  nb.mask = nb.index >= 0;
  nb.prepare(points, points);
  nb.compact(1);
  ASSERT_TRUE(nb.active_list);
  EXPECT_TRUE(torch::equal(nb.active, torch::tensor({0, 1})));
  EXPECT_TRUE(torch::equal(nb.active_list->index, torch::tensor({{1, -1}, {0, -1}})));
  NeighborTensors few_idle = nb;  // two rows without neighbours, fewer than asked for
  few_idle.compact(3);
  EXPECT_FALSE(few_idle.active_list);
}

}  // namespace
}  // namespace dynscope
