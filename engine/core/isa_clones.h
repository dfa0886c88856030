// Instruction-set clones of a hot function: GCC function multiversioning compiles it for the
// x86-64 levels v4 (AVX-512) and v3 (AVX2+FMA) and for the baseline the build targets (SSE2), and
// picks the clone once at load time from the CPU's features. Levels, not CPU models: a clone for
// a model ("arch=skylake-avx512", "arch=haswell") is chosen only on that vendor's model, so every
// AMD CPU ran the baseline. Other compilers and targets build the plain function.
#pragma once

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define DYNSCOPE_ISA_V4 "arch=x86-64-v4"
#define DYNSCOPE_ISA_V3 "arch=x86-64-v3"
#define DYNSCOPE_ISA_CLONES \
  __attribute__((target_clones(DYNSCOPE_ISA_V4, DYNSCOPE_ISA_V3, "default")))
#else
#define DYNSCOPE_ISA_CLONES
#endif

namespace dynscope {

/// The x86-64 level whose clones this CPU runs: "x86-64-v4" (AVX-512), "x86-64-v3" (AVX2+FMA) or
/// "baseline", by the same load-time dispatch as DYNSCOPE_ISA_CLONES.
const char* isa_level();

/// Whether this CPU's clones have 32 vector registers of 64 bytes (x86-64-v4). A clone's kernels
/// that keep blocks of 16-float or 8-double vectors in registers do so only there: with 16
/// registers of 32 bytes (AVX2) or 16 bytes such a vector takes two or four, and GCC moves arrays
/// of them through memory at every operation, so those kernels use narrower blocks instead.
bool wide_vector_registers();

}  // namespace dynscope
