// create_context: maps a backend name to a concrete context; the only file that includes them.
#include "render/context_factory.h"

#include "engine/core/error.h"
#include "render/gl_functions.h"
#include "render/glfw_context.h"
#include "render/osmesa_context.h"

namespace dynscope::render {

std::vector<std::string> context_backends() { return {"osmesa", "glfw"}; }

std::unique_ptr<GlContext> create_context(const std::string& backend, int width, int height,
                                          bool visible) {
  if (backend == "osmesa") return std::make_unique<OsMesaContext>(width, height);
  if (backend == "glfw") return std::make_unique<GlfwContext>(width, height, "dynscope", visible);
  throw ValueError("context backend", "'" + backend + "' is not one of osmesa, glfw");
}

std::string describe_backend(const std::string& backend) {
  const std::unique_ptr<GlContext> context = create_context(backend, 1, 1);
  GlFunctions gl;
  gl.load(*context);
  return gl.describe();
}

}  // namespace dynscope::render
