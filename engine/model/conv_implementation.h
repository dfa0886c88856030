// Which formulation the neighbour convolutions run: the fused ops or the unfused reference.
#pragma once

namespace dynscope {

/// kFused: the fused aggregation / gather ops with hand-written backward passes and the neighbour
/// quantities prepared once per list (the default). kUnfused: the plain LibTorch formulation
/// (gather, concatenate, batched matmul, relative positions per convolution), kept as the
/// reference that tests and benchmarks compare the fused path against.
/// kFusedBaseline: the fused ops with their kernels compiled for the baseline x86-64 instruction
/// set only (SSE2), which kFused replaces on CPUs with AVX2+FMA or AVX-512 (kernels cloned per
/// instruction set and chosen at load time); kept so tests and benchmarks can compare the two.
/// kFusedComposed: the fused aggregation with the PointConv's WeightNet and positional embedding
/// as LibTorch ops before it (the formulation point_conv_aggregate_mlp replaced), kept likewise.
enum class ConvImplementation { kFused, kUnfused, kFusedBaseline, kFusedComposed };

/// The formulation every PointConv and GnnConv of this process runs (process-wide).
ConvImplementation conv_implementation();
/// Selects it for subsequent forward passes.
void set_conv_implementation(ConvImplementation implementation);

/// The instruction-set clone of the fused kernels this CPU runs under kFused: "x86-64-v4"
/// (AVX-512), "x86-64-v3" (AVX2+FMA) or "baseline", chosen by the same load-time dispatch as the
/// kernels themselves.
const char* fused_kernel_isa();

/// The register arrangement the fused kernels run (kernel_blocking(), engine/core/isa_clones.h):
/// "wide" or "narrow".
const char* fused_kernel_blocking();

}  // namespace dynscope
