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

/// How the cloned kernels keep their running sums in vector registers. kAuto follows the clone
/// this CPU runs: kWide under AVX-512, whose 32 registers of 64 bytes hold blocks of 16-float or
/// 8-double vectors, kNarrow under AVX2 and the baseline, where such a vector takes two or four of
/// 16 registers and GCC moves arrays of them through memory at every operation, so the kernels use
/// vectors of 32 bytes instead. kWide and kNarrow force one arrangement (process-wide), so tests
/// and benchmarks can run both on any CPU; their results agree to rounding.
enum class KernelBlocking { kAuto, kWide, kNarrow };
KernelBlocking kernel_blocking();
void set_kernel_blocking(KernelBlocking blocking);

/// Whether the kernels run their wide arrangement: kernel_blocking() resolved on this CPU.
bool wide_vector_registers();

}  // namespace dynscope
