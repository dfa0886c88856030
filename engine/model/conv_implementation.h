// Which formulation the neighbour convolutions run: the fused ops or the unfused reference.
#pragma once

namespace dynscope {

/// kFused: the fused aggregation / gather ops with hand-written backward passes and the neighbour
/// quantities prepared once per list (the default). kUnfused: the plain LibTorch formulation
/// (gather, concatenate, batched matmul, relative positions per convolution), kept as the
/// reference that tests and benchmarks compare the fused path against.
enum class ConvImplementation { kFused, kUnfused };

/// The formulation every PointConv and GnnConv of this process runs (process-wide).
ConvImplementation conv_implementation();
/// Selects it for subsequent forward passes.
void set_conv_implementation(ConvImplementation implementation);

}  // namespace dynscope
