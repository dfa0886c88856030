// adam_step: torch::optim::Adam::step's update written as one pass over each parameter.
#include "engine/train/adam_step.h"

#include <c10/util/string_utils.h>

#include <cmath>
#include <memory>
#include <string>

#include "engine/core/isa_clones.h"

namespace dynscope {
namespace {

bool fusable(const torch::Tensor& t) {
  return t.defined() && t.scalar_type() == torch::kFloat && t.device().is_cpu() &&
         t.is_contiguous() && !t.is_sparse();
}

// The key torch::optim::Adam files a parameter's state under.
std::string state_key(const torch::Tensor& p) {
  return c10::guts::to_string(p.unsafeGetTensorImpl());
}

struct AdamScalars {
  float b1, b2, one_minus_b1, one_minus_b2, root_correction2, eps, decay, step_size;
};

// The update of one parameter's n floats. Compiled with -fno-math-errno (a square root need not
// set errno, which kept the loop scalar: a sixth of a Physion-scale training step) and
// -ffp-contract=off (no multiply-add contraction in the clones, so every clone rounds as the
// baseline and as LibTorch's Adam did: square root, division, products and sums are each
// rounded once, vectors or not); see CMakeLists.txt.
DYNSCOPE_ISA_CLONES
void adam_update(float* __restrict w, const float* __restrict g, float* __restrict m,
                 float* __restrict v, int64_t n, const AdamScalars& k) {
  for (int64_t i = 0; i < n; ++i) {
    const float gi = k.decay != 0.0f ? g[i] + k.decay * w[i] : g[i];
    m[i] = m[i] * k.b1 + k.one_minus_b1 * gi;
    v[i] = v[i] * k.b2 + k.one_minus_b2 * gi * gi;
    const float denom = std::sqrt(v[i]) / k.root_correction2 + k.eps;
    w[i] += k.step_size * (m[i] / denom);
  }
}

}  // namespace

void adam_step(torch::optim::Adam& optimizer) {
  for (const torch::optim::OptimizerParamGroup& group : optimizer.param_groups()) {
    const auto& options = static_cast<const torch::optim::AdamOptions&>(group.options());
    if (options.amsgrad()) return static_cast<void>(optimizer.step());
    for (const torch::Tensor& p : group.params()) {
      if (!p.grad().defined()) continue;
      bool ok = fusable(p) && fusable(p.grad());
      // Moments loaded from a saved state must match the parameter's layout too.
      const auto found = optimizer.state().find(state_key(p));
      if (ok && found != optimizer.state().end()) {
        const auto& state = static_cast<const torch::optim::AdamParamState&>(*found->second);
        ok = fusable(state.exp_avg()) && fusable(state.exp_avg_sq()) &&
             state.exp_avg().numel() == p.numel() && state.exp_avg_sq().numel() == p.numel();
      }
      if (!ok) return static_cast<void>(optimizer.step());
    }
  }
  torch::NoGradGuard no_grad;
  auto& states = optimizer.state();
  for (torch::optim::OptimizerParamGroup& group : optimizer.param_groups()) {
    const auto& options = static_cast<const torch::optim::AdamOptions&>(group.options());
    const double beta1 = std::get<0>(options.betas()), beta2 = std::get<1>(options.betas());
    for (torch::Tensor& p : group.params()) {
      const torch::Tensor grad = p.grad();
      if (!grad.defined()) continue;
      const std::string key = state_key(p);
      auto found = states.find(key);
      if (found == states.end()) {
        auto fresh = std::make_unique<torch::optim::AdamParamState>();
        fresh->step(0);
        fresh->exp_avg(torch::zeros_like(p, torch::MemoryFormat::Preserve));
        fresh->exp_avg_sq(torch::zeros_like(p, torch::MemoryFormat::Preserve));
        found = states.emplace(key, std::move(fresh)).first;
      }
      auto& state = static_cast<torch::optim::AdamParamState&>(*found->second);
      state.step(state.step() + 1);
      const auto step = static_cast<double>(state.step());
      // The scalars as Adam's tensor ops see them: computed in double, applied in float.
      const double correction1 = 1.0 - std::pow(beta1, step);
      const double correction2 = 1.0 - std::pow(beta2, step);
      const auto b1 = static_cast<float>(beta1), b2 = static_cast<float>(beta2);
      const auto one_minus_b1 = static_cast<float>(1.0 - beta1);
      const auto one_minus_b2 = static_cast<float>(1.0 - beta2);
      const auto root_correction2 = static_cast<float>(std::sqrt(correction2));
      const auto eps = static_cast<float>(options.eps());
      const auto decay = static_cast<float>(options.weight_decay());
      const auto step_size = static_cast<float>(-options.lr() / correction1);
      const AdamScalars k{b1, b2, one_minus_b1, one_minus_b2, root_correction2, eps, decay,
                          step_size};
      adam_update(p.data_ptr<float>(), grad.data_ptr<float>(), state.exp_avg().data_ptr<float>(),
                  state.exp_avg_sq().data_ptr<float>(), p.numel(), k);
      p.unsafeGetTensorImpl()->bump_version();  // as the in-place op it replaces would
    }
  }
}

}  // namespace dynscope
