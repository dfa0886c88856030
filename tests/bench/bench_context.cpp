// Adds the machine context (cores, threads, the BLAS actually mapped, LibTorch) to the header of
// every benchmark program, before main runs, so each printed table says what it was measured on.
#include <benchmark/benchmark.h>

#include "engine/model/torch_runtime.h"

namespace dynscope {
namespace {

const bool kRegistered = [] {
  for (const auto& [key, value] : torch_context()) benchmark::AddCustomContext(key, value);
  return true;
}();

}  // namespace
}  // namespace dynscope
