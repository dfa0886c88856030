// GLSL sources from shaders/, embedded into the binary at build time (render/embed_shaders.cmake).
#pragma once

#include <string>
#include <vector>

namespace dynscope::render {

/// One embedded shader file: its name in shaders/ ("points.vert") and its full source text.
struct EmbeddedShader {
  const char* name;
  const char* source;
};

/// Every shader file of shaders/, sorted by name.
const std::vector<EmbeddedShader>& embedded_shaders();

/// Source of the embedded shader `name`; throws ValueError listing the known names if missing.
const char* embedded_shader_source(const std::string& name);

}  // namespace dynscope::render
