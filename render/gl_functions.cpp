// GlFunctions: loads the entry-point table through the current context's get_proc_address.
#include "render/gl_functions.h"

#include <cstdio>

#include "engine/core/error.h"
#include "render/gl_context.h"

namespace dynscope::render {

void GlFunctions::load(GlContext& context) {
#define DYNSCOPE_GL_LOAD(upper, name)                                                         \
  name = reinterpret_cast<PFNGL##upper##PROC>(context.get_proc_address("gl" #name));          \
  if (!name) {                                                                                \
    throw Error(context.backend() + " context: GL entry point gl" #name " is not available"); \
  }
  DYNSCOPE_GL_FUNCTIONS(DYNSCOPE_GL_LOAD)
#undef DYNSCOPE_GL_LOAD
}

std::string GlFunctions::describe() const {
  auto text = [this](GLenum what) {
    const GLubyte* s = GetString(what);
    return s ? std::string(reinterpret_cast<const char*>(s)) : std::string("?");
  };
  return "GL " + text(GL_VERSION) + " / " + text(GL_RENDERER);
}

void GlFunctions::check(const char* what) const {
  GLenum first = GetError();
  if (first == GL_NO_ERROR) return;
  // Drain the queue so the next check reports only new errors.
  for (int i = 0; i < 16 && GetError() != GL_NO_ERROR; ++i) {
  }
  char code[16];
  std::snprintf(code, sizeof(code), "0x%04x", first);
  throw Error(std::string("GL error ") + code + " after " + what);
}

}  // namespace dynscope::render
