// Picks a concrete GlContext by name at run time (the only place that knows the backends).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "render/gl_context.h"

namespace dynscope::render {

/// Backend names accepted by create_context: "osmesa" (headless) and "glfw" (window).
std::vector<std::string> context_backends();

/// Creates and makes current a context of `backend` with a width x height framebuffer. A "glfw"
/// window is shown only when `visible`. Throws ValueError for an unknown backend name and Error
/// when the backend cannot create a context (so a front end can fall back to "osmesa").
std::unique_ptr<GlContext> create_context(const std::string& backend, int width, int height,
                                          bool visible = false);

/// "GL <version> / <renderer>" of a 1x1 context of `backend` (e.g. "GL 4.5 (Core Profile) Mesa
/// 22.3.6 / llvmpipe (LLVM 15.0.6, 256 bits)"). Throws as create_context.
std::string describe_backend(const std::string& backend);

}  // namespace dynscope::render
