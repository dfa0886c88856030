// isa_level: which instruction-set clone of the hot kernels this CPU runs.
#include "engine/core/isa_clones.h"

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

}  // namespace

const char* isa_level() { return isa_of_this_cpu(); }

bool wide_vector_registers() {
  static const bool wide = std::strcmp(isa_level(), "x86-64-v4") == 0;
  return wide;
}

}  // namespace dynscope
