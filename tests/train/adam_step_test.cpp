// adam_step against torch::optim::Adam::step: the same parameters and optimiser state after
// several steps, with weight decay, two groups and a parameter without a gradient; a state saved
// after fused steps continues identically under either; the fallback for what it does not fuse
// (double parameters, AMSGrad, moments not laid out like their parameter).
#include "engine/train/adam_step.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <cmath>
#include <sstream>
#include <string>
#include <vector>

namespace dynscope {
namespace {

// Two identical parameter sets: [8,5] and [5] in group 0, [3,4] in group 1, [6] never given a
// gradient.
std::vector<torch::Tensor> make_params(torch::ScalarType dtype) {
  torch::manual_seed(3);
  std::vector<torch::Tensor> ps{torch::randn({8, 5}), torch::randn({5}), torch::randn({3, 4}),
                                torch::randn({6})};
  for (torch::Tensor& p : ps) p = p.to(dtype).requires_grad_(true);
  return ps;
}

torch::optim::Adam make_adam(const std::vector<torch::Tensor>& ps, double weight_decay) {
  std::vector<torch::optim::OptimizerParamGroup> groups;
  groups.emplace_back(std::vector<torch::Tensor>{ps[0], ps[1], ps[3]},
                      std::make_unique<torch::optim::AdamOptions>(
                          torch::optim::AdamOptions(5e-3).weight_decay(weight_decay)));
  groups.emplace_back(
      std::vector<torch::Tensor>{ps[2]},
      std::make_unique<torch::optim::AdamOptions>(
          torch::optim::AdamOptions(1e-2).betas(std::make_tuple(0.8, 0.99)).eps(1e-6)));
  return torch::optim::Adam(groups, torch::optim::AdamOptions(1e-3));
}

// Gradients of step s, the same for both parameter sets (the unused [6] gets none).
void set_grads(std::vector<torch::Tensor>& ps, int s) {
  torch::manual_seed(100 + s);
  for (size_t i = 0; i < 3; ++i) {
    ps[i].mutable_grad() = torch::randn(ps[i].sizes()).to(ps[i].scalar_type()) * (1.0 + s);
  }
}

void expect_same(const std::vector<torch::Tensor>& a, const std::vector<torch::Tensor>& b,
                 const std::string& what) {
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_TRUE(torch::allclose(a[i], b[i], 1e-6, 1e-7))
        << what << ": parameter " << i << " differs by " << (a[i] - b[i]).abs().max();
  }
}

const torch::optim::AdamParamState& state_of(torch::optim::Adam& adam, const torch::Tensor& p) {
  return static_cast<const torch::optim::AdamParamState&>(
      *adam.state().at(c10::guts::to_string(p.unsafeGetTensorImpl())));
}

TEST(AdamStepTest, MatchesLibTorchsAdamStepByStep) {
  for (double decay : {0.0, 0.01}) {
    std::vector<torch::Tensor> ref = make_params(torch::kFloat), fused = make_params(torch::kFloat);
    torch::optim::Adam ref_adam = make_adam(ref, decay), fused_adam = make_adam(fused, decay);
    const torch::Tensor untouched = fused[3].detach().clone();
    for (int s = 0; s < 6; ++s) {
      set_grads(ref, s);
      set_grads(fused, s);
      ref_adam.step();
      adam_step(fused_adam);
      expect_same(ref, fused, "step " + std::to_string(s) + " decay " + std::to_string(decay));
    }
    // The optimiser state is the one Adam keeps: step count and both moments per parameter.
    for (size_t i = 0; i < 3; ++i) {
      const auto& a = state_of(ref_adam, ref[i]);
      const auto& b = state_of(fused_adam, fused[i]);
      EXPECT_EQ(a.step(), b.step());
      EXPECT_TRUE(torch::allclose(a.exp_avg(), b.exp_avg(), 1e-6, 1e-8));
      EXPECT_TRUE(torch::allclose(a.exp_avg_sq(), b.exp_avg_sq(), 1e-6, 1e-10));
    }
    // A parameter without a gradient is neither moved nor given a state, as in Adam.
    EXPECT_TRUE(torch::equal(fused[3].detach(), untouched));
    EXPECT_EQ(fused_adam.state().count(c10::guts::to_string(fused[3].unsafeGetTensorImpl())), 0u);
    EXPECT_EQ(fused_adam.state().size(), ref_adam.state().size());
  }
}

// The update of a large parameter (the vector loop of the CPU's instruction-set clone, with a
// tail) is the scalar update written out here, bit for bit: its clones are compiled without
// multiply-add contraction, and square roots, divisions, products and sums are each rounded once
// whatever the vector width.
TEST(AdamStepTest, VectorUpdateEqualsTheScalarFormulaBitForBit) {
  torch::manual_seed(7);
  torch::Tensor p = torch::randn({1003}).requires_grad_(true);
  std::vector<float> w(p.data_ptr<float>(), p.data_ptr<float>() + p.numel());
  std::vector<float> m(w.size(), 0.0f), v(w.size(), 0.0f);
  const double lr = 3e-3, beta1 = 0.9, beta2 = 0.999, eps = 1e-8, decay = 0.02;
  torch::optim::Adam adam({p}, torch::optim::AdamOptions(lr).weight_decay(decay));
  for (int step = 1; step <= 3; ++step) {
    p.mutable_grad() = torch::randn({1003}) * static_cast<double>(step);
    const float* g = p.grad().data_ptr<float>();
    const double c1 = 1.0 - std::pow(beta1, step), c2 = 1.0 - std::pow(beta2, step);
    const auto root_c2 = static_cast<float>(std::sqrt(c2));
    const auto step_size = static_cast<float>(-lr / c1);
    for (size_t i = 0; i < w.size(); ++i) {
      volatile float gi = g[i] + static_cast<float>(decay) * w[i];  // no contraction here either
      volatile float mi = m[i] * static_cast<float>(beta1);
      m[i] = mi + static_cast<float>(1.0 - beta1) * gi;
      volatile float vi = v[i] * static_cast<float>(beta2);
      volatile float g2 = static_cast<float>(1.0 - beta2) * gi;
      volatile float g2g = g2 * gi;
      v[i] = vi + g2g;
      volatile float root = std::sqrt(v[i]);
      volatile float denom = root / root_c2 + static_cast<float>(eps);
      volatile float ratio = m[i] / denom;
      volatile float delta = step_size * ratio;
      w[i] = w[i] + delta;
    }
    adam_step(adam);
    const float* got = p.data_ptr<float>();
    for (size_t i = 0; i < w.size(); ++i) {
      ASSERT_EQ(got[i], w[i]) << "step " << step << " element " << i;
    }
  }
}

TEST(AdamStepTest, SavedStateContinuesUnderEitherStep) {
  std::vector<torch::Tensor> a = make_params(torch::kFloat);
  torch::optim::Adam adam = make_adam(a, 0.0);
  for (int s = 0; s < 3; ++s) {
    set_grads(a, s);
    adam_step(adam);
  }
  std::ostringstream saved;
  {
    torch::serialize::OutputArchive archive;
    adam.save(archive);
    archive.save_to(saved);
  }
  // A fresh optimiser over a copy of the parameters, loaded from what the fused steps saved.
  std::vector<torch::Tensor> b;
  for (const torch::Tensor& p : a) b.push_back(p.detach().clone().requires_grad_(true));
  torch::optim::Adam loaded = make_adam(b, 0.0);
  {
    std::istringstream in(saved.str());
    torch::serialize::InputArchive archive;
    archive.load_from(in);
    loaded.load(archive);
  }
  for (int s = 3; s < 6; ++s) {
    set_grads(a, s);
    set_grads(b, s);
    adam_step(adam);
    loaded.step();
    expect_same(a, b, "resumed step " + std::to_string(s));
  }
}

TEST(AdamStepTest, FallsBackToAdamForWhatItDoesNotFuse) {
  // Double parameters and AMSGrad take LibTorch's own step, with the same result.
  std::vector<torch::Tensor> ref = make_params(torch::kDouble), fused = make_params(torch::kDouble);
  torch::optim::Adam ref_adam = make_adam(ref, 0.0), fused_adam = make_adam(fused, 0.0);
  for (int s = 0; s < 3; ++s) {
    set_grads(ref, s);
    set_grads(fused, s);
    ref_adam.step();
    adam_step(fused_adam);
  }
  expect_same(ref, fused, "double");
  std::vector<torch::Tensor> r2 = make_params(torch::kFloat), f2 = make_params(torch::kFloat);
  torch::optim::Adam r2_adam(std::vector<torch::Tensor>{r2[0]},
                             torch::optim::AdamOptions(1e-2).amsgrad(true));
  torch::optim::Adam f2_adam(std::vector<torch::Tensor>{f2[0]},
                             torch::optim::AdamOptions(1e-2).amsgrad(true));
  for (int s = 0; s < 3; ++s) {
    set_grads(r2, s);
    set_grads(f2, s);
    r2_adam.step();
    adam_step(f2_adam);
  }
  expect_same({r2[0]}, {f2[0]}, "amsgrad");
  // Moments in another layout than the parameter (as a state file could hold): still Adam's step.
  std::vector<torch::Tensor> r3 = make_params(torch::kFloat), f3 = make_params(torch::kFloat);
  torch::optim::Adam r3_adam = make_adam(r3, 0.0), f3_adam = make_adam(f3, 0.0);
  for (int s = 0; s < 3; ++s) {
    set_grads(r3, s);
    set_grads(f3, s);
    r3_adam.step();
    adam_step(f3_adam);
    if (s == 1) {
      auto& state = static_cast<torch::optim::AdamParamState&>(
          *f3_adam.state().at(c10::guts::to_string(f3[0].unsafeGetTensorImpl())));
      state.exp_avg(state.exp_avg().t().contiguous().t());  // same values, not contiguous
      ASSERT_FALSE(state.exp_avg().is_contiguous());
    }
  }
  expect_same(r3, f3, "non-contiguous moments");
}

}  // namespace
}  // namespace dynscope
