// ImGuiRenderer: draws Dear ImGui's draw data through our GL table (works under OSMesa and GLFW).
#pragma once

#include "render/gl_functions.h"
#include "render/shader_program.h"

struct ImDrawData;

namespace dynscope::render {
class GlContext;
}

namespace dynscope::app::viewer {

/// Draws ImGui draw lists into the current context's default framebuffer with the embedded
/// imgui.vert/imgui.frag pair, a font-atlas texture, one streamed vertex/index buffer and scissor
/// rectangles. ImGui's own OpenGL3 backend loads GL through libGL and fails under OSMesa; this one
/// uses the context's get_proc_address like the rest of render/.
class ImGuiRenderer {
 public:
  /// Loads GL from `context` (made current), compiles the shaders and uploads the font atlas of
  /// the current ImGui context (ImGui::CreateContext must have run). Throws Error on GL failure.
  explicit ImGuiRenderer(render::GlContext& context);
  ~ImGuiRenderer();
  ImGuiRenderer(const ImGuiRenderer&) = delete;
  ImGuiRenderer& operator=(const ImGuiRenderer&) = delete;

  /// Draws `data` (from ImGui::GetDrawData) over what the framebuffer holds; alpha stays opaque.
  void render(const ImDrawData* data);

 private:
  using ScissorFn = void (*)(GLint, GLint, GLsizei, GLsizei);

  render::GlFunctions gl_;
  ScissorFn scissor_ = nullptr;  ///< glScissor is not in render's table; loaded here.
  render::ShaderProgram program_;
  GLuint font_texture_ = 0;
  GLuint vao_ = 0, vbo_ = 0, ibo_ = 0;
};

}  // namespace dynscope::app::viewer
