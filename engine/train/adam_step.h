// One Adam update of every parameter as one loop per parameter: the arithmetic and the state of
// torch::optim::Adam::step (the same AdamParamState entries, so saving, loading and resuming the
// optimiser are unchanged) without its seven LibTorch ops per parameter.
#pragma once

#include <torch/optim/adam.h>

namespace dynscope {

/// Applies one step of `optimizer` to every parameter with a gradient, as
/// torch::optim::Adam::step does (moments, bias corrections, weight decay, per-group options),
/// in float32 loops over contiguous CPU parameters. Falls back to `optimizer.step()` when a
/// parameter, its gradient or its saved moments are not contiguous float32 CPU tensors or a group
/// asks for AMSGrad.
void adam_step(torch::optim::Adam& optimizer);

}  // namespace dynscope
