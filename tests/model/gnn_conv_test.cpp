// GnnConv (DPI-style message passing): reference formula, masking, empty neighbourhoods.
#include "engine/model/gnn_conv.h"

#include <gtest/gtest.h>
#include <torch/types.h>
#include <torch/utils.h>

namespace dynscope {
namespace {

struct Case {
  torch::Tensor query, source, xs, xq;
  NeighborTensors nb;
};

Case make_case(uint64_t seed) {
  torch::manual_seed(seed);
  Case cs;
  cs.source = torch::rand({15, 3}, torch::kFloat64);
  cs.query = torch::rand({6, 3}, torch::kFloat64);
  cs.xs = torch::randn({15, 4});
  cs.xq = torch::randn({6, 4});
  cs.nb.index = torch::randint(0, 14, {6, 5}, torch::kInt64);  // never point 14
  cs.nb.mask = torch::rand({6, 5}) > 0.3;
  cs.nb.mask[0] = false;
  cs.nb.mask.index_put_({1, 0}, true);
  cs.nb.index = torch::where(cs.nb.mask, cs.nb.index, torch::full_like(cs.nb.index, -1));
  return cs;
}

TEST(GnnConvTest, MatchesMessagePassingReference) {
  torch::NoGradGuard no_grad;
  const Case cs = make_case(1);
  GnnConv conv(GnnConvOptions(4, 5).normalize(true));
  const torch::Tensor y = conv->forward(cs.query, cs.source, cs.xs, cs.xq, cs.nb);
  for (int64_t i = 1; i < 6; ++i) {
    torch::Tensor sum = torch::zeros({5});
    int count = 0;
    for (int64_t j = 0; j < 5; ++j) {
      if (!cs.nb.mask[i][j].item<bool>()) continue;
      const int64_t s = cs.nb.index[i][j].item<int64_t>();
      const torch::Tensor d = (cs.source[s] - cs.query[i]).to(torch::kFloat);
      sum += conv->edge_mlp->forward(torch::cat({cs.xq[i], cs.xs[s], d}).unsqueeze(0))[0];
      ++count;
    }
    const torch::Tensor expected =
        conv->node_mlp->forward(torch::cat({cs.xq[i], sum / count}).unsqueeze(0))[0];
    EXPECT_TRUE(torch::allclose(y[i], expected, 1e-4, 1e-5)) << "row " << i;
  }
}

TEST(GnnConvTest, MaskedNeighboursContributeNothingAndEmptyRowsAreZero) {
  torch::NoGradGuard no_grad;
  const Case cs = make_case(2);
  GnnConv conv(GnnConvOptions(4, 3));
  const torch::Tensor before = conv->forward(cs.query, cs.source, cs.xs, cs.xq, cs.nb);
  EXPECT_TRUE(torch::equal(before[0], torch::zeros({3})));
  NeighborTensors nb = cs.nb;
  nb.index = torch::where(nb.mask, nb.index, torch::full_like(nb.index, 14));
  torch::Tensor xs = cs.xs.clone();
  xs[14] = 100.0;
  const torch::Tensor after = conv->forward(cs.query, cs.source, xs, cs.xq, nb);
  EXPECT_TRUE(torch::allclose(before, after, 1e-6, 1e-6));
}

TEST(GnnConvTest, BackwardReachesEveryParameter) {
  const Case cs = make_case(3);
  GnnConv conv(GnnConvOptions(4, 3));
  conv->forward(cs.query, cs.source, cs.xs, cs.xq, cs.nb).square().sum().backward();
  for (const auto& p : conv->named_parameters()) {
    ASSERT_TRUE(p.value().grad().defined()) << p.key();
    EXPECT_TRUE(torch::isfinite(p.value().grad()).all().item<bool>()) << p.key();
  }
}

}  // namespace
}  // namespace dynscope
