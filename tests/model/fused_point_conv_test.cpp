// Fused ops against the unfused formulation (gather, mask, batched matmul) and finite differences;
// PointConv and GnnConv against their unfused reference formulation (ConvImplementation).
#include "engine/model/fused_point_conv.h"

#include <ATen/Parallel.h>
#include <gtest/gtest.h>
#include <torch/autograd.h>
#include <torch/nn/functional/activation.h>
#include <torch/nn/modules/linear.h>

#include <functional>
#include <string>
#include <vector>

#include "engine/core/error.h"
#include "engine/core/isa_clones.h"
#include "engine/model/conv_implementation.h"
#include "engine/model/gnn_conv.h"
#include "engine/model/neighbor_tensors.h"
#include "engine/model/point_conv.h"

namespace dynscope {
namespace {

struct Inputs {
  torch::Tensor features, edge, h, index, mask;
};

// Random inputs with masked entries (−1), one row without any valid neighbour, and repeated
// sources (so the backward scatter accumulates several contributions into one row).
Inputs make_inputs(int64_t n, int64_t m, int64_t k, int64_t c, int64_t p, int64_t j,
                   torch::ScalarType dtype, uint64_t seed) {
  torch::manual_seed(seed);
  Inputs in;
  const auto opt = torch::TensorOptions(dtype);
  in.features = torch::randn({n, c}, opt);
  in.edge = p > 0 ? torch::randn({m, k, p}, opt) : torch::Tensor();
  in.h = torch::randn({m, k, j}, opt);
  in.mask = torch::rand({m, k}) > 0.3;
  in.mask[0] = false;
  in.index = torch::where(in.mask, torch::randint(0, n, {m, k}, torch::kInt64),
                          torch::full({m, k}, -1, torch::kInt64));
  return in;
}

// The unfused formulation the fused op replaces: gather, concatenate, mask h, batched matmul.
torch::Tensor reference_aggregate(const torch::Tensor& features, const torch::Tensor& edge,
                                  const torch::Tensor& h, const torch::Tensor& index,
                                  const torch::Tensor& mask) {
  torch::Tensor x = gather_neighbors(features, index);
  if (edge.defined()) x = torch::cat({x, edge}, -1);
  const torch::Tensor hm = h * mask.unsqueeze(-1).to(h.scalar_type());
  const torch::Tensor agg = torch::matmul(hm.transpose(1, 2), x);
  return agg.reshape({h.size(0), agg.size(1) * agg.size(2)});
}

std::vector<torch::Tensor> grads_of(const torch::Tensor& out, const torch::Tensor& weight,
                                    std::vector<torch::Tensor> wrt) {
  std::vector<torch::Tensor> defined;
  for (const auto& t : wrt)
    if (t.defined()) defined.push_back(t);
  return torch::autograd::grad({(out * weight).sum()}, defined);
}

TEST(FusedPointConvTest, AggregateMatchesUnfusedForwardAndGradientsInFloat) {
  for (int64_t p : {0, 4}) {
    Inputs in = make_inputs(40, 25, 7, 6, p, 5, torch::kFloat, 1 + p);
    for (torch::Tensor* t : {&in.features, &in.edge, &in.h}) {
      if (t->defined()) t->requires_grad_(true);
    }
    const torch::Tensor fused = point_conv_aggregate(in.features, in.edge, in.h, in.index);
    const torch::Tensor ref = reference_aggregate(in.features, in.edge, in.h, in.index, in.mask);
    ASSERT_EQ(fused.sizes(), ref.sizes());
    EXPECT_TRUE(torch::allclose(fused, ref, 1e-5, 1e-5)) << (fused - ref).abs().max();
    EXPECT_TRUE(torch::equal(fused[0], torch::zeros_like(fused[0])));
    const torch::Tensor w = torch::randn_like(ref);
    const auto gf = grads_of(fused, w, {in.features, in.edge, in.h});
    const auto gr = grads_of(ref, w, {in.features, in.edge, in.h});
    ASSERT_EQ(gf.size(), gr.size());
    for (size_t i = 0; i < gf.size(); ++i) {
      EXPECT_TRUE(torch::allclose(gf[i], gr[i], 1e-5, 1e-5))
          << "gradient " << i << " differs by " << (gf[i] - gr[i]).abs().max();
    }
  }
}

// Central differences of sum(w · f(x)) against the analytic gradient, every element, in double
// (what torch.autograd.gradcheck does for one random output weighting).
void expect_gradcheck(const std::function<torch::Tensor(const std::vector<torch::Tensor>&)>& f,
                      std::vector<torch::Tensor> inputs) {
  for (auto& t : inputs) t.requires_grad_(true);
  const torch::Tensor out = f(inputs);
  const torch::Tensor w = torch::randn_like(out);
  const auto analytic = torch::autograd::grad({(out * w).sum()}, inputs);
  const double eps = 1e-6;
  torch::NoGradGuard no_grad;
  for (size_t i = 0; i < inputs.size(); ++i) {
    torch::Tensor x = inputs[i].detach().clone();
    std::vector<torch::Tensor> probe = inputs;
    auto flat = x.view({-1});
    torch::Tensor numeric = torch::zeros_like(flat);
    for (int64_t e = 0; e < flat.numel(); ++e) {
      const double v = flat[e].item<double>();
      flat[e] = v + eps;
      probe[i] = x;
      const double up = (f(probe) * w).sum().item<double>();
      flat[e] = v - eps;
      const double down = (f(probe) * w).sum().item<double>();
      flat[e] = v;
      numeric[e] = (up - down) / (2 * eps);
    }
    EXPECT_TRUE(torch::allclose(analytic[i].reshape({-1}), numeric, 1e-6, 1e-7))
        << "input " << i << ": max difference "
        << (analytic[i].reshape({-1}) - numeric).abs().max();
  }
}

// The kernels cloned per instruction set (AVX-512, AVX2+FMA) against the same kernels compiled
// for the baseline instruction set, at the filter widths with their own code paths (16, 8) and
// another (5), with and without per-edge channels.
TEST(FusedPointConvTest, InstructionSetClonesMatchTheBaselineKernels) {
  for (int64_t j : {16, 8, 5}) {
    for (int64_t p : {0, 8}) {
      Inputs in = make_inputs(300, 200, 11, 12, p, j, torch::kFloat, 10 + j + p);
      for (torch::Tensor* t : {&in.features, &in.edge, &in.h}) {
        if (t->defined()) t->requires_grad_(true);
      }
      const torch::Tensor w = torch::randn({200, j * (12 + p)});
      auto run = [&](ConvImplementation impl) {
        set_conv_implementation(impl);
        const torch::Tensor out = point_conv_aggregate(in.features, in.edge, in.h, in.index);
        std::vector<torch::Tensor> all{out};
        for (const torch::Tensor& g : grads_of(out, w, {in.features, in.edge, in.h})) {
          all.push_back(g);
        }
        set_conv_implementation(ConvImplementation::kFused);
        return all;
      };
      const auto simd = run(ConvImplementation::kFused);
      const auto baseline = run(ConvImplementation::kFusedBaseline);
      ASSERT_EQ(simd.size(), baseline.size());
      for (size_t i = 0; i < simd.size(); ++i) {
        EXPECT_TRUE(torch::allclose(simd[i], baseline[i], 1e-5, 1e-5))
            << "J " << j << " P " << p << " tensor " << i << " differs by "
            << (simd[i] - baseline[i]).abs().max();
      }
    }
  }
  Inputs in = make_inputs(50, 40, 6, 1, 0, 1, torch::kFloat, 4);
  const torch::Tensor q = torch::randn({40, 24}), s = torch::randn({50, 24});
  const torch::Tensor r = torch::randn({40, 6, 24});
  const torch::Tensor simd = gather_add(q, s, r, in.index);
  set_conv_implementation(ConvImplementation::kFusedBaseline);
  const torch::Tensor baseline = gather_add(q, s, r, in.index);
  set_conv_implementation(ConvImplementation::kFused);
  EXPECT_TRUE(torch::allclose(simd, baseline, 1e-6, 1e-6));
}

// The kernels run the best clone this CPU supports, whatever its vendor: clones named after one
// vendor's CPU models ("arch=skylake-avx512") once left every AMD CPU on the baseline.
TEST(FusedPointConvTest, TheKernelsRunTheCloneOfThisCpusInstructionSetLevel) {
  const std::string isa = fused_kernel_isa();
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
  const char* expected = __builtin_cpu_supports("x86-64-v4")   ? "x86-64-v4"
                         : __builtin_cpu_supports("x86-64-v3") ? "x86-64-v3"
                                                               : "baseline";
  EXPECT_EQ(isa, expected);
#else
  EXPECT_EQ(isa, "baseline");
#endif
}

TEST(FusedPointConvTest, AggregatePassesGradcheckInDouble) {
  const Inputs in = make_inputs(6, 4, 3, 2, 2, 3, torch::kDouble, 7);
  expect_gradcheck(
      [&](const std::vector<torch::Tensor>& v) {
        return point_conv_aggregate(v[0], v[1], v[2], in.index);
      },
      {in.features, in.edge, in.h});
}

TEST(FusedPointConvTest, ResultDoesNotDependOnThreadCount) {
  const Inputs in = make_inputs(500, 400, 9, 8, 4, 6, torch::kFloat, 3);
  const int before = at::get_num_threads();
  at::set_num_threads(1);
  const torch::Tensor one = point_conv_aggregate(in.features, in.edge, in.h, in.index);
  at::set_num_threads(2);
  const torch::Tensor two = point_conv_aggregate(in.features, in.edge, in.h, in.index);
  at::set_num_threads(before);
  EXPECT_TRUE(torch::equal(one, two));
}

TEST(FusedPointConvTest, AggregateRejectsBadInputs) {
  const Inputs in = make_inputs(10, 5, 3, 4, 2, 3, torch::kFloat, 4);
  torch::Tensor far = in.index.clone();
  far[1][0] = 10;
  EXPECT_THROW(point_conv_aggregate(in.features, in.edge, in.h, far), ValueError);
  EXPECT_THROW(point_conv_aggregate(in.features, in.edge, in.h.to(torch::kDouble), in.index),
               ValueError);
  EXPECT_THROW(point_conv_aggregate(in.features, in.edge.narrow(0, 0, 4), in.h, in.index),
               ValueError);
  EXPECT_THROW(point_conv_aggregate(in.features, in.edge, in.h, in.index.to(torch::kInt32)),
               ValueError);
}

torch::Tensor reference_gather_add(const torch::Tensor& q, const torch::Tensor& s,
                                   const torch::Tensor& r, const torch::Tensor& mask,
                                   const torch::Tensor& index) {
  const torch::Tensor sum = q.unsqueeze(1) + gather_neighbors(s, index) + r;
  return sum * mask.unsqueeze(-1).to(q.scalar_type());
}

TEST(FusedPointConvTest, GatherAddMatchesUnfusedAndPassesGradcheck) {
  Inputs in = make_inputs(30, 20, 5, 1, 0, 1, torch::kFloat, 5);
  torch::Tensor q = torch::randn({20, 6}).requires_grad_(true);
  torch::Tensor s = torch::randn({30, 6}).requires_grad_(true);
  torch::Tensor r = torch::randn({20, 5, 6}).requires_grad_(true);
  const torch::Tensor fused = gather_add(q, s, r, in.index);
  const torch::Tensor ref = reference_gather_add(q, s, r, in.mask, in.index);
  EXPECT_TRUE(torch::allclose(fused, ref, 1e-6, 1e-6));
  const torch::Tensor w = torch::randn_like(ref);
  const auto gf = grads_of(fused, w, {q, s, r});
  const auto gr = grads_of(ref, w, {q, s, r});
  for (size_t i = 0; i < gf.size(); ++i) {
    EXPECT_TRUE(torch::allclose(gf[i], gr[i], 1e-5, 1e-5)) << "gradient " << i;
  }
  const Inputs small = make_inputs(5, 4, 3, 1, 0, 1, torch::kDouble, 6);
  expect_gradcheck(
      [&](const std::vector<torch::Tensor>& v) {
        return gather_add(v[0], v[1], v[2], small.index);
      },
      {torch::randn({4, 2}, torch::kDouble), torch::randn({5, 2}, torch::kDouble),
       torch::randn({4, 3, 2}, torch::kDouble)});
}

// Runs the neighbour convolutions on the unfused reference formulation while alive.
struct UnfusedScope {
  UnfusedScope() { set_conv_implementation(ConvImplementation::kUnfused); }
  ~UnfusedScope() { set_conv_implementation(ConvImplementation::kFused); }
};

struct ConvCase {
  torch::Tensor query, source, features;
  NeighborTensors nb;
};

ConvCase make_conv_case(int64_t n, int64_t m, int64_t k, int64_t c, uint64_t seed) {
  const Inputs in = make_inputs(n, m, k, c, 0, 1, torch::kFloat, seed);
  ConvCase cs;
  cs.source = torch::rand({n, 3}, torch::kFloat64) * 0.3 + 100.0;  // far from the origin
  cs.query = torch::rand({m, 3}, torch::kFloat64) * 0.3 + 100.0;
  cs.features = in.features.clone().requires_grad_(true);
  cs.nb.index = in.index;
  cs.nb.mask = in.mask;
  return cs;
}

void expect_same_gradients(torch::nn::Module& module, const torch::Tensor& fused,
                           const torch::Tensor& ref, const torch::Tensor& features) {
  const torch::Tensor w = torch::randn_like(ref);
  std::vector<torch::Tensor> wrt = module.parameters();
  wrt.push_back(features);
  const auto gf = torch::autograd::grad({(fused * w).sum()}, wrt, {}, true, false, true);
  const auto gr = torch::autograd::grad({(ref * w).sum()}, wrt, {}, true, false, true);
  for (size_t i = 0; i < wrt.size(); ++i) {
    const bool df = gf[i].defined(), dr = gr[i].defined();
    if (!df && !dr) continue;
    const torch::Tensor a = df ? gf[i] : torch::zeros_like(gr[i]);
    const torch::Tensor b = dr ? gr[i] : torch::zeros_like(gf[i]);
    EXPECT_TRUE(torch::allclose(a, b, 1e-5, 1e-5))
        << "gradient of input " << i << " differs by " << (a - b).abs().max();
  }
}

TEST(FusedPointConvTest, PointConvMatchesItsUnfusedFormulation) {
  for (bool normalize : {false, true}) {
    for (int64_t pos : {0, 4}) {
      ConvCase cs = make_conv_case(40, 30, 6, 5, normalize ? 11 : 12);
      PointConv conv(
          PointConvOptions(5, 7).c_mid(4).pos_channels(pos).normalize(normalize).position_scale(
              0.25));
      torch::Tensor ref;
      {
        UnfusedScope unfused;
        ref = conv->forward(cs.query, cs.source, cs.features, cs.nb);
      }
      const torch::Tensor fused = conv->forward(cs.query, cs.source, cs.features, cs.nb);
      EXPECT_TRUE(torch::allclose(fused, ref, 1e-5, 1e-5)) << (fused - ref).abs().max();
      {
        // Inference: the linear runs inside the aggregation op.
        torch::NoGradGuard no_grad;
        const torch::Tensor inferred = conv->forward(cs.query, cs.source, cs.features, cs.nb);
        EXPECT_TRUE(torch::allclose(inferred, ref, 1e-5, 1e-5)) << (inferred - ref).abs().max();
      }
      // The same through a prepared list (what a hierarchy's forward pass uses).
      NeighborTensors prepared = cs.nb;
      prepared.prepare(cs.query, cs.source);
      const torch::Tensor again = conv->forward(cs.query, cs.source, cs.features, prepared);
      EXPECT_TRUE(torch::allclose(again, ref, 1e-5, 1e-5)) << (again - ref).abs().max();
      expect_same_gradients(*conv, fused, ref, cs.features);
    }
  }
}

// The gradients of the fused MLP aggregation and of its reference, for one random output
// gradient, in the features, the gate when there is one and every weight of the WeightNet and
// of the embedding when there is one.
std::pair<std::vector<torch::Tensor>, std::vector<torch::Tensor>> mlp_gradients(
    const torch::Tensor& fused, const torch::Tensor& ref, const ConvCase& cs,
    const torch::Tensor& gate, PointConv conv) {
  std::vector<torch::Tensor> wrt{cs.features};
  if (gate.defined()) wrt.push_back(gate);
  for (const torch::Tensor& p : conv->weightnet->parameters()) wrt.push_back(p);
  if (conv->pos_embed) {
    for (const torch::Tensor& p : conv->pos_embed->parameters()) wrt.push_back(p);
  }
  const torch::Tensor w = torch::randn_like(ref);
  return {grads_of(fused, w, wrt), grads_of(ref, w, wrt)};
}

// The MLP aggregation composed of LibTorch ops and point_conv_aggregate: the reference.
torch::Tensor mlp_composition(const ConvCase& cs, const torch::Tensor& rel, PointConv conv,
                              const torch::Tensor& gate, const torch::Tensor& index) {
  torch::Tensor h = conv->weightnet->forward(rel);
  if (gate.defined()) h = h * gate.unsqueeze(-1);
  const torch::Tensor edge = conv->pos_embed ? conv->pos_embed->forward(rel) : torch::Tensor();
  return point_conv_aggregate(cs.features, edge, h, index);
}

// point_conv_aggregate_mlp_linear against the aggregation followed by torch::mm: without
// gradients (the linear inside the op, four queries at a time: 50 queries leave two over) for
// output counts below, at and past multiples of 4 and the kernels' channel arrangements; with
// gradients (the two ops) the same values and a gradient in the linear's weight; a weight of
// the wrong shape is refused. Each case also runs with a third of the rows left without
// neighbours (as relational lists leave most rows), alone and in runs, inside and across groups
// of four and at the end: those rows are exactly zero and the rows around them unchanged.
TEST(FusedPointConvTest, TheMlpAggregationWithItsLinearMatchesTheTwoOps) {
  const std::vector<int64_t> emptied{0, 2, 3, 4, 7, 9, 10, 11, 12, 13, 14, 20, 31, 45, 47, 48, 49};
  for (bool sparse : {false, true}) {
    for (int64_t c_mid : {16, 4}) {
      for (bool gated : {false, true}) {
        for (int64_t pos : {0, 8}) {
          for (int64_t channels : {6, 8, 45}) {
            ConvCase cs = make_conv_case(60, 50, 7, channels, 40 + c_mid + gated + pos + channels);
            PointConv conv(PointConvOptions(channels, 9).c_mid(c_mid).pos_channels(pos));
            NeighborTensors nb = cs.nb;
            nb.prepare(cs.query, cs.source);
            const torch::Tensor rel = nb.rel * 3.0f;
            torch::Tensor index = masked_index(nb);
            if (sparse) {
              index = index.clone();
              for (int64_t q : emptied) index[q].fill_(-1);
            }
            const torch::Tensor gate =
                gated ? torch::rand({nb.rows(), index.size(1)}) : torch::Tensor();
            const int64_t n_in = c_mid * (channels + pos);
            for (int64_t n_out : {1, 4, 9, 32}) {
              const torch::Tensor weight = torch::randn({n_out, n_in});
              torch::Tensor fused, ref;
              {
                torch::NoGradGuard no_grad;
                fused = point_conv_aggregate_mlp_linear(cs.features, rel, conv->edge_mlps(), gate,
                                                        index, weight);
                ref = torch::mm(
                    point_conv_aggregate_mlp(cs.features, rel, conv->edge_mlps(), gate, index),
                    weight.t());
              }
              ASSERT_EQ(fused.sizes(), ref.sizes());
              EXPECT_TRUE(torch::allclose(fused, ref, 1e-4, 1e-5))
                  << "c_mid " << c_mid << " gated " << gated << " pos " << pos << " channels "
                  << channels << " outputs " << n_out << " sparse " << sparse << ": "
                  << (fused - ref).abs().max();
              if (sparse) {
                for (int64_t q : emptied) {
                  EXPECT_TRUE(torch::equal(fused[q], torch::zeros({n_out}))) << "row " << q;
                }
              }
            }
            const torch::Tensor weight = torch::randn({3, n_in}).requires_grad_(true);
            const torch::Tensor with_grad = point_conv_aggregate_mlp_linear(
                cs.features, rel, conv->edge_mlps(), gate, index, weight);
            EXPECT_TRUE(with_grad.requires_grad());
            with_grad.sum().backward();
            ASSERT_TRUE(weight.grad().defined());
            EXPECT_GT(weight.grad().abs().sum().item<float>(), 0.0f);
            EXPECT_THROW(point_conv_aggregate_mlp_linear(cs.features, rel, conv->edge_mlps(), gate,
                                                         index, torch::zeros({3, n_in + 1})),
                         ValueError);
          }
        }
      }
    }
  }
}

// point_conv_aggregate_mlp (edge MLPs evaluated inside the aggregation, forward and backward)
// against its composition from LibTorch ops and point_conv_aggregate: outputs and gradients in
// features, gate and every MLP weight, at the default filter width 16 and at 4, with and without
// a gate and a positional embedding. The feature counts give the model's sizes' kernel every
// arrangement of its channel blocks (with the embedding's 8 or without: 6 + 8 and 6 rows padded
// to 16 and 8, 8 + 8 one block of 16 and 8 one of 8, 32 + 8 blocks of 16 and 8, 45 + 8 and 45
// padded to 56 and 48).
TEST(FusedPointConvTest, TheMlpAggregationMatchesItsComposition) {
  for (int64_t c_mid : {16, 4}) {
    for (bool gated : {false, true}) {
      for (int64_t pos : {0, 8}) {
        for (int64_t channels : {6, 8, 32, 45}) {
          if (c_mid == 4 && channels != 6) continue;  // the general kernel has no blocks
          ConvCase cs = make_conv_case(60, 50, 7, channels, 20 + c_mid + gated + pos + channels);
          PointConv conv(PointConvOptions(channels, 9).c_mid(c_mid).pos_channels(pos));
          NeighborTensors nb = cs.nb;
          nb.prepare(cs.query, cs.source);
          const torch::Tensor rel = nb.rel * 3.0f;
          const torch::Tensor index = masked_index(nb);
          torch::Tensor gate;
          if (gated) gate = torch::rand({nb.rows(), nb.index.size(1)}).requires_grad_(true);
          const torch::Tensor fused =
              point_conv_aggregate_mlp(cs.features, rel, conv->edge_mlps(), gate, index);
          const torch::Tensor ref = mlp_composition(cs, rel, conv, gate, index);
          ASSERT_EQ(fused.sizes(), ref.sizes());
          EXPECT_TRUE(torch::allclose(fused, ref, 1e-5, 1e-5))
              << "channels " << channels << ": " << (fused - ref).abs().max();
          const auto [gf, gr] = mlp_gradients(fused, ref, cs, gate, conv);
          ASSERT_EQ(gf.size(), gr.size());
          for (size_t i = 0; i < gf.size(); ++i) {
            EXPECT_TRUE(torch::allclose(gf[i], gr[i], 1e-4, 1e-5))
                << "c_mid " << c_mid << " gated " << gated << " pos " << pos << " channels "
                << channels << " gradient " << i << " differs by " << (gf[i] - gr[i]).abs().max();
          }
        }
      }
    }
  }
  EdgeMlps none;
  EXPECT_THROW(point_conv_aggregate_mlp(torch::zeros({3, 2}), torch::zeros({2, 2, 3}), none, {},
                                        torch::zeros({2, 2}, torch::kInt64)),
               ValueError);
}

// The arranged inference kernel keeps its sums in registers in 16-row blocks of 16 floats where
// the CPU has AVX-512's 32 wide registers and in 8-row blocks of 8 floats elsewhere (a 16-float
// vector is two AVX2 registers, and GCC moved arrays of them through memory at every product).
// Both arrangements run on any CPU when forced: each against the composition of LibTorch ops,
// forward and backward, and without gradients with and without the linear inside (four queries at a
// time, with outputs past a multiple of the sums kept per row), a gate and an embedding, at channel
// counts that give every block arrangement. kAuto follows the instruction-set level.
TEST(FusedPointConvTest, BothRegisterBlockingsMatchTheComposition) {
  EXPECT_EQ(kernel_blocking(), KernelBlocking::kAuto);
  EXPECT_STREQ(fused_kernel_blocking(),
               std::string(fused_kernel_isa()) == "x86-64-v4" ? "wide" : "narrow");
  for (KernelBlocking blocking : {KernelBlocking::kWide, KernelBlocking::kNarrow}) {
    set_kernel_blocking(blocking);
    EXPECT_STREQ(fused_kernel_blocking(), blocking == KernelBlocking::kWide ? "wide" : "narrow");
    for (bool gated : {false, true}) {
      for (int64_t pos : {0, 8}) {
        for (int64_t channels : {6, 8, 32, 45}) {
          ConvCase cs = make_conv_case(60, 50, 7, channels, 70 + gated + pos + channels);
          PointConv conv(PointConvOptions(channels, 9).c_mid(16).pos_channels(pos));
          NeighborTensors nb = cs.nb;
          nb.prepare(cs.query, cs.source);
          const torch::Tensor rel = nb.rel * 3.0f;
          const torch::Tensor index = masked_index(nb);
          torch::Tensor gate;
          if (gated) gate = torch::rand({nb.rows(), index.size(1)}).requires_grad_(true);
          const torch::Tensor ref = mlp_composition(cs, rel, conv, gate, index);
          const torch::Tensor fused =
              point_conv_aggregate_mlp(cs.features, rel, conv->edge_mlps(), gate, index);
          EXPECT_TRUE(torch::allclose(fused, ref, 1e-5, 1e-5))
              << fused_kernel_blocking() << " channels " << channels << " pos " << pos << ": "
              << (fused - ref).abs().max();
          // The backward kernel's arrangements: gradients in the features, the gate and every
          // weight of the WeightNet and the embedding.
          const auto [gf, gr] = mlp_gradients(fused, ref, cs, gate, conv);
          ASSERT_EQ(gf.size(), gr.size());
          // Relative to each gradient's largest entry: a bias's gradient sums over every edge,
          // and an entry where those sums cancel has no precision of its own.
          for (size_t i = 0; i < gf.size(); ++i) {
            const float diff = (gf[i] - gr[i]).abs().max().item<float>();
            const float scale = gr[i].abs().max().item<float>();
            EXPECT_LE(diff, 1e-4f * scale + 1e-5f)
                << fused_kernel_blocking() << " channels " << channels << " pos " << pos
                << " gated " << gated << " gradient " << i << " (largest entry " << scale << ")";
          }
          torch::NoGradGuard no_grad;
          for (int64_t n_out : {3, 9, 32}) {
            const torch::Tensor weight = torch::randn({n_out, ref.size(1)});
            const torch::Tensor linear = point_conv_aggregate_mlp_linear(
                cs.features, rel, conv->edge_mlps(), gate, index, weight);
            const torch::Tensor expected = torch::mm(ref, weight.t());
            EXPECT_TRUE(torch::allclose(linear, expected, 1e-4, 1e-4))
                << fused_kernel_blocking() << " channels " << channels << " pos " << pos
                << " outputs " << n_out << ": " << (linear - expected).abs().max();
          }
        }
      }
    }
  }
  set_kernel_blocking(KernelBlocking::kAuto);
}

TEST(FusedPointConvTest, GnnConvMatchesItsUnfusedFormulation) {
  for (bool normalize : {false, true}) {
    ConvCase cs = make_conv_case(35, 20, 5, 6, normalize ? 21 : 22);
    GnnConv gnn(GnnConvOptions(6, 5).normalize(normalize).position_scale(0.5));
    const torch::Tensor xq = torch::randn({20, 6}).requires_grad_(true);
    torch::Tensor ref;
    {
      UnfusedScope unfused;
      ref = gnn->forward(cs.query, cs.source, cs.features, xq, cs.nb);
    }
    const torch::Tensor fused = gnn->forward(cs.query, cs.source, cs.features, xq, cs.nb);
    EXPECT_TRUE(torch::allclose(fused, ref, 1e-5, 1e-5)) << (fused - ref).abs().max();
    expect_same_gradients(*gnn, fused, ref, cs.features);
  }
}

}  // namespace
}  // namespace dynscope

namespace dynscope {
namespace {

// layer_norm_relu against torch::layer_norm followed by ReLU: without gradients it runs our row
// kernel (its instruction-set clone and its baseline), with gradients the LibTorch ops, whose
// gradients flow; rows of a large and a tiny spread, widths of the model (32) and odd ones.
TEST(FusedPointConvTest, LayerNormReluMatchesLibTorch) {
  torch::manual_seed(5);
  for (int64_t c : {32, 24, 7, 2}) {
    torch::Tensor x = torch::randn({1000, c}) * 3.0 + 1.5;
    x.slice(0, 0, 10).mul_(1e-4);  // nearly constant rows: the variance is tiny
    const torch::Tensor w = torch::randn({c}), b = torch::randn({c});
    const torch::Tensor ref = torch::relu(torch::layer_norm(x, {c}, w, b, 1e-5));
    {
      torch::NoGradGuard no_grad;
      for (ConvImplementation impl :
           {ConvImplementation::kFused, ConvImplementation::kFusedBaseline}) {
        set_conv_implementation(impl);
        const torch::Tensor y = layer_norm_relu(x, w, b, 1e-5);
        set_conv_implementation(ConvImplementation::kFused);
        EXPECT_TRUE(torch::allclose(y, ref, 1e-5, 1e-5))
            << "C " << c << " differs by " << (y - ref).abs().max();
      }
    }
    // With gradients to record: the LibTorch ops, so the gradient is LibTorch's.
    const torch::Tensor xg = x.clone().requires_grad_(true);
    const torch::Tensor y = layer_norm_relu(xg, w, b, 1e-5);
    EXPECT_TRUE(y.requires_grad());
    EXPECT_TRUE(torch::equal(y.detach(), ref));
    y.sum().backward();
    const torch::Tensor xr = x.clone().requires_grad_(true);
    torch::relu(torch::layer_norm(xr, {c}, w, b, 1e-5)).sum().backward();
    EXPECT_TRUE(torch::equal(xg.grad(), xr.grad()));
  }
}

}  // namespace
}  // namespace dynscope
