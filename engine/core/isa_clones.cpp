// isa_level: which instruction-set clone of the hot kernels this CPU runs.
#include "engine/core/isa_clones.h"

#include <atomic>
#include <cstring>

namespace dynscope {
namespace {

// One version per clone of DYNSCOPE_ISA_CLONES, dispatched by the same rule.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
__attribute__((target("default"))) const char* isa_of_this_cpu() { return "baseline"; }
__attribute__((target(DYNSCOPE_ISA_V3))) const char* isa_of_this_cpu() { return "x86-64-v3"; }
__attribute__((target(DYNSCOPE_ISA_V4))) const char* isa_of_this_cpu() { return "x86-64-v4"; }
#else
const char* isa_of_this_cpu() { return "baseline"; }
#endif

std::atomic<KernelBlocking> g_blocking{KernelBlocking::kAuto};

}  // namespace

const char* isa_level() { return isa_of_this_cpu(); }

KernelBlocking kernel_blocking() { return g_blocking.load(); }

void set_kernel_blocking(KernelBlocking blocking) { g_blocking.store(blocking); }

bool wide_vector_registers() {
  static const bool v4 = std::strcmp(isa_level(), "x86-64-v4") == 0;
  switch (g_blocking.load(std::memory_order_relaxed)) {
    case KernelBlocking::kWide:
      return true;
    case KernelBlocking::kNarrow:
      return false;
    case KernelBlocking::kAuto:
      break;
  }
  return v4;
}

}  // namespace dynscope
