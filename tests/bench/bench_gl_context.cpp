// Adds the headless GL renderer string to the header of the benchmark programs that draw.
#include <benchmark/benchmark.h>

#include <exception>
#include <string>

#include "render/context_factory.h"

namespace dynscope {
namespace {

const bool kRegistered = [] {
  std::string gl;
  try {
    gl = render::describe_backend("osmesa");
  } catch (const std::exception& e) {
    gl = std::string("unavailable: ") + e.what();
  }
  benchmark::AddCustomContext("gl_headless", gl);
  return true;
}();

}  // namespace
}  // namespace dynscope
