// PointConv: the efficient form equals the naive eq. (1), masking and normalisation.
#include "engine/model/point_conv.h"

#include <gtest/gtest.h>
#include <torch/types.h>
#include <torch/utils.h>

#include "engine/core/error.h"
#include "engine/core/rng.h"

namespace dynscope {
namespace {

struct Case {
  torch::Tensor query, source, features;
  NeighborTensors nb;
};

// Random source/query points and a neighbour list with some masked entries (−1) and one row
// with no valid neighbour.
Case make_case(int64_t n, int64_t m, int64_t k, int64_t c, uint64_t seed) {
  torch::manual_seed(seed);
  Case cs;
  cs.source = torch::rand({n, 3}, torch::kFloat64);
  cs.query = torch::rand({m, 3}, torch::kFloat64);
  cs.features = torch::randn({n, c});
  cs.nb.index = torch::randint(0, n - 1, {m, k}, torch::kInt64);  // never the last point
  cs.nb.mask = torch::rand({m, k}) > 0.3;
  cs.nb.mask[0] = false;
  cs.nb.mask.index_put_({1, 0}, true);
  cs.nb.index = torch::where(cs.nb.mask, cs.nb.index, torch::full_like(cs.nb.index, -1));
  return cs;
}

// Naive eq. (1): y_0 = Σ_k W(p_k − p_0)ᵀ x_k + b with W(d)[c][o] = Σ_m W_l[o][m·C + c] h_m(d),
// built explicitly from the layer's weights, in double precision.
torch::Tensor naive(PointConvImpl& conv, const Case& cs) {
  const auto& opt = conv.options();
  const int64_t c_total = opt.in_channels() + opt.pos_channels();
  const int64_t m = cs.nb.index.size(0), k = cs.nb.index.size(1);
  const torch::Tensor wl = conv.linear->weight.to(torch::kDouble);  // [C_out, c_mid·C]
  const torch::Tensor b = conv.linear->bias.to(torch::kDouble);
  torch::Tensor out = torch::zeros({m, opt.out_channels()}, torch::kDouble);
  for (int64_t i = 0; i < m; ++i) {
    int64_t count = 0;
    torch::Tensor y = torch::zeros({opt.out_channels()}, torch::kDouble);
    for (int64_t j = 0; j < k; ++j) {
      if (!cs.nb.mask[i][j].item<bool>()) continue;
      ++count;
      const int64_t src = cs.nb.index[i][j].item<int64_t>();
      const torch::Tensor d =
          ((cs.source[src] - cs.query[i]) / opt.position_scale()).to(torch::kFloat).unsqueeze(0);
      const torch::Tensor h = conv.weightnet->forward(d)[0].to(torch::kDouble);  // [c_mid]
      torch::Tensor x = cs.features[src].to(torch::kDouble);
      if (conv.pos_embed) {
        x = torch::cat({x, conv.pos_embed->forward(d)[0].to(torch::kDouble)});
      }
      // W(d) as an explicit [C, C_out] matrix.
      torch::Tensor w = torch::zeros({c_total, opt.out_channels()}, torch::kDouble);
      for (int64_t mm = 0; mm < opt.c_mid(); ++mm) {
        w += h[mm] * wl.narrow(1, mm * c_total, c_total).t();
      }
      y += torch::matmul(w.t(), x);
    }
    if (count > 0) {
      if (opt.normalize()) y /= static_cast<double>(count);
      out[i] = y + b;
    }
  }
  return out;
}

TEST(PointConvTest, EfficientFormEqualsNaiveEquationOne) {
  torch::NoGradGuard no_grad;
  const Case cs = make_case(30, 12, 6, 5, 1);
  PointConv conv(PointConvOptions(5, 7).c_mid(4));
  const torch::Tensor y = conv->forward(cs.query, cs.source, cs.features, cs.nb);
  ASSERT_EQ(y.sizes(), (std::vector<int64_t>{12, 7}));
  EXPECT_TRUE(torch::allclose(y.to(torch::kDouble), naive(*conv, cs), 1e-4, 1e-5));
}

TEST(PointConvTest, EfficientFormEqualsNaiveWithPositionalEmbeddingAndScale) {
  torch::NoGradGuard no_grad;
  const Case cs = make_case(25, 9, 8, 3, 2);
  PointConv conv(PointConvOptions(3, 6).c_mid(5).pos_channels(4).position_scale(0.5));
  const torch::Tensor y = conv->forward(cs.query, cs.source, cs.features, cs.nb);
  EXPECT_TRUE(torch::allclose(y.to(torch::kDouble), naive(*conv, cs), 1e-4, 1e-5));
}

TEST(PointConvTest, NormalizedFormDividesByValidCount) {
  torch::NoGradGuard no_grad;
  const Case cs = make_case(25, 9, 8, 3, 3);
  PointConv conv(PointConvOptions(3, 4).c_mid(3).normalize(true));
  const torch::Tensor y = conv->forward(cs.query, cs.source, cs.features, cs.nb);
  EXPECT_TRUE(torch::allclose(y.to(torch::kDouble), naive(*conv, cs), 1e-4, 1e-5));
}

TEST(PointConvTest, MaskedNeighboursContributeNothing) {
  torch::NoGradGuard no_grad;
  Case cs = make_case(20, 10, 6, 4, 4);
  PointConv conv(PointConvOptions(4, 5).pos_channels(3));
  const torch::Tensor before = conv->forward(cs.query, cs.source, cs.features, cs.nb);
  // Point masked entries at real points and change those points' features and positions:
  // only rows that use them as *valid* neighbours may change, and here none does.
  NeighborTensors nb = cs.nb;
  nb.index = torch::where(nb.mask, nb.index, torch::full_like(nb.index, 19));
  const torch::Tensor used =
      torch::zeros({20}, torch::kBool).index_fill_(0, nb.index.masked_select(nb.mask), true);
  ASSERT_FALSE(used[19].item<bool>()) << "seed gives a valid use of point 19; change the seed";
  torch::Tensor features = cs.features.clone();
  features[19] = 1e3;
  torch::Tensor source = cs.source.clone();
  source[19] = -5.0;
  const torch::Tensor after = conv->forward(cs.query, source, features, nb);
  EXPECT_TRUE(torch::allclose(before, after, 1e-6, 1e-6));
}

TEST(PointConvTest, RowWithoutValidNeighboursIsExactlyZero) {
  torch::NoGradGuard no_grad;
  const Case cs = make_case(20, 5, 4, 3, 5);
  PointConv conv(PointConvOptions(3, 6).normalize(true));
  const torch::Tensor y = conv->forward(cs.query, cs.source, cs.features, cs.nb);
  EXPECT_TRUE(torch::equal(y[0], torch::zeros({6})));
  EXPECT_GT(y[1].abs().sum().item<float>(), 0.0f);
}

TEST(PointConvTest, FilterWeightsAreZeroWhereMasked) {
  torch::NoGradGuard no_grad;
  const Case cs = make_case(20, 6, 5, 3, 6);
  PointConv conv(PointConvOptions(3, 2).c_mid(4));
  const torch::Tensor h = conv->filter_weights(cs.query, cs.source, cs.nb);
  ASSERT_EQ(h.sizes(), (std::vector<int64_t>{6, 5, 4}));
  const torch::Tensor masked = h.masked_select(cs.nb.mask.logical_not().unsqueeze(-1));
  EXPECT_TRUE(torch::equal(masked, torch::zeros_like(masked)));
}

TEST(PointConvTest, PermutingSourcePointsLeavesOutputUnchanged) {
  torch::NoGradGuard no_grad;
  const Case cs = make_case(20, 8, 5, 3, 7);
  PointConv conv(PointConvOptions(3, 4).pos_channels(2));
  const torch::Tensor y = conv->forward(cs.query, cs.source, cs.features, cs.nb);
  const torch::Tensor perm = torch::randperm(20, torch::kInt64);
  const torch::Tensor inverse = torch::argsort(perm);
  NeighborTensors nb = cs.nb;
  nb.index = torch::where(
      nb.mask, inverse.index_select(0, nb.index.clamp_min(0).flatten()).view_as(nb.index),
      nb.index);
  const torch::Tensor y2 = conv->forward(cs.query, cs.source.index_select(0, perm),
                                         cs.features.index_select(0, perm), nb);
  EXPECT_TRUE(torch::allclose(y, y2, 1e-5, 1e-6));
}

TEST(PointConvTest, RejectsWrongChannelCount) {
  const Case cs = make_case(10, 4, 3, 3, 8);
  PointConv conv(PointConvOptions(5, 2));
  EXPECT_THROW(conv->forward(cs.query, cs.source, cs.features, cs.nb), ValueError);
}

}  // namespace
}  // namespace dynscope
