// adam_step: torch::optim::Adam::step's update written as one pass over each parameter.
#include "engine/train/adam_step.h"

#include <c10/util/string_utils.h>

#include <cmath>
#include <memory>
#include <string>

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
      float* __restrict w = p.data_ptr<float>();
      const float* __restrict g = grad.data_ptr<float>();
      float* __restrict m = state.exp_avg().data_ptr<float>();
      float* __restrict v = state.exp_avg_sq().data_ptr<float>();
      const int64_t n = p.numel();
#pragma omp simd
      for (int64_t i = 0; i < n; ++i) {
        const float gi = decay != 0.0f ? g[i] + decay * w[i] : g[i];
        m[i] = m[i] * b1 + one_minus_b1 * gi;
        v[i] = v[i] * b2 + one_minus_b2 * gi * gi;
        const float denom = std::sqrt(v[i]) / root_correction2 + eps;
        w[i] += step_size * (m[i] / denom);
      }
      p.unsafeGetTensorImpl()->bump_version();  // as the in-place op it replaces would
    }
  }
}

}  // namespace dynscope
