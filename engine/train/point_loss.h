// The training loss over a batch's points.
#pragma once

#include <torch/torch.h>

#include "engine/core/types.h"

namespace dynscope {

/// Σ over points and components of the Huber loss (transition `delta`) of (predicted − truth) /
/// target_std, for `[P,3]` float64 positions (p̂ − p equals the target's error, so dividing by the
/// target std makes delta scale-free). When `moving` `[P,1]` (float, 1 or 0) is defined, the rows
/// where it is 0 add nothing and get no gradient: the static points of a model that holds them
/// (ModelConfig::hold_static). The caller divides by the points it counts.
torch::Tensor point_loss_sum(const torch::Tensor& predicted, const torch::Tensor& truth,
                             const Vec3& target_std, double delta, const torch::Tensor& moving);

}  // namespace dynscope
