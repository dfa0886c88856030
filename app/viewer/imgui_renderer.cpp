// ImGui draw data → GL through render's function table (see imgui_renderer.h).
#include "app/viewer/imgui_renderer.h"

#include <imgui.h>

#include <cstddef>

#include "engine/core/error.h"
#include "render/gl_context.h"

namespace dynscope::app::viewer {

ImGuiRenderer::ImGuiRenderer(render::GlContext& context) {
  context.make_current();
  gl_.load(context);
  scissor_ = reinterpret_cast<ScissorFn>(context.get_proc_address("glScissor"));
  if (scissor_ == nullptr) {
    throw Error("imgui renderer: GL entry point glScissor is missing (" + context.backend() + ")");
  }
  program_ = render::ShaderProgram::from_embedded(gl_, "imgui.vert", "imgui.frag");

  ImGuiIO& io = ImGui::GetIO();
  io.BackendRendererName = "dynscope_render";
  unsigned char* pixels = nullptr;
  int width = 0, height = 0;
  io.Fonts->GetTexDataAsRGBA32(&pixels, &width, &height);
  gl_.GenTextures(1, &font_texture_);
  gl_.BindTexture(GL_TEXTURE_2D, font_texture_);
  gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  gl_.PixelStorei(GL_UNPACK_ALIGNMENT, 1);
  gl_.TexImage2D(GL_TEXTURE_2D, 0, GL_RGBA, width, height, 0, GL_RGBA, GL_UNSIGNED_BYTE, pixels);
  io.Fonts->SetTexID(reinterpret_cast<ImTextureID>(static_cast<intptr_t>(font_texture_)));

  gl_.GenVertexArrays(1, &vao_);
  gl_.GenBuffers(1, &vbo_);
  gl_.GenBuffers(1, &ibo_);
  gl_.BindVertexArray(vao_);
  gl_.BindBuffer(GL_ARRAY_BUFFER, vbo_);
  gl_.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, ibo_);
  const GLsizei stride = sizeof(ImDrawVert);
  gl_.EnableVertexAttribArray(0);
  gl_.VertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, stride,
                          reinterpret_cast<void*>(offsetof(ImDrawVert, pos)));
  gl_.EnableVertexAttribArray(1);
  gl_.VertexAttribPointer(1, 2, GL_FLOAT, GL_FALSE, stride,
                          reinterpret_cast<void*>(offsetof(ImDrawVert, uv)));
  gl_.EnableVertexAttribArray(2);
  gl_.VertexAttribPointer(2, 4, GL_UNSIGNED_BYTE, GL_TRUE, stride,
                          reinterpret_cast<void*>(offsetof(ImDrawVert, col)));
  gl_.BindVertexArray(0);
  gl_.check("imgui renderer setup");
}

ImGuiRenderer::~ImGuiRenderer() {
  if (ImGui::GetCurrentContext() != nullptr) ImGui::GetIO().Fonts->SetTexID(ImTextureID{});
  gl_.DeleteTextures(1, &font_texture_);
  gl_.DeleteBuffers(1, &vbo_);
  gl_.DeleteBuffers(1, &ibo_);
  gl_.DeleteVertexArrays(1, &vao_);
}

void ImGuiRenderer::render(const ImDrawData* data) {
  if (data == nullptr) return;
  const float fb_w = data->DisplaySize.x * data->FramebufferScale.x;
  const float fb_h = data->DisplaySize.y * data->FramebufferScale.y;
  if (fb_w <= 0 || fb_h <= 0) return;
  gl_.BindFramebuffer(GL_FRAMEBUFFER, 0);
  gl_.Viewport(0, 0, static_cast<GLsizei>(fb_w), static_cast<GLsizei>(fb_h));
  gl_.Enable(GL_BLEND);
  // Colour blends by alpha; destination alpha stays 1 so screenshots are opaque.
  gl_.BlendFuncSeparate(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
  gl_.Disable(GL_CULL_FACE);
  gl_.Disable(GL_DEPTH_TEST);
  gl_.Enable(GL_SCISSOR_TEST);
  program_.use();
  program_.set("u_display_pos", data->DisplayPos.x, data->DisplayPos.y);
  program_.set("u_display_size", data->DisplaySize.x, data->DisplaySize.y);
  program_.set("u_texture", 0);
  gl_.ActiveTexture(GL_TEXTURE0);
  gl_.BindVertexArray(vao_);
  gl_.BindBuffer(GL_ARRAY_BUFFER, vbo_);
  gl_.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, ibo_);

  const ImVec2 clip_off = data->DisplayPos;
  const ImVec2 clip_scale = data->FramebufferScale;
  constexpr GLenum kIndexType = sizeof(ImDrawIdx) == 2 ? GL_UNSIGNED_SHORT : GL_UNSIGNED_INT;
  for (int n = 0; n < data->CmdListsCount; ++n) {
    const ImDrawList* list = data->CmdLists[n];
    gl_.BufferData(GL_ARRAY_BUFFER,
                   static_cast<GLsizeiptr>(list->VtxBuffer.Size) * sizeof(ImDrawVert),
                   list->VtxBuffer.Data, GL_STREAM_DRAW);
    gl_.BufferData(GL_ELEMENT_ARRAY_BUFFER,
                   static_cast<GLsizeiptr>(list->IdxBuffer.Size) * sizeof(ImDrawIdx),
                   list->IdxBuffer.Data, GL_STREAM_DRAW);
    for (int c = 0; c < list->CmdBuffer.Size; ++c) {
      const ImDrawCmd& cmd = list->CmdBuffer[c];
      if (cmd.UserCallback != nullptr) {
        // ImGui's sentinel asks the renderer to restore its state; other callbacks run as given.
        if (cmd.UserCallback != ImDrawCallback_ResetRenderState) cmd.UserCallback(list, &cmd);
        continue;
      }
      const float x0 = (cmd.ClipRect.x - clip_off.x) * clip_scale.x;
      const float y0 = (cmd.ClipRect.y - clip_off.y) * clip_scale.y;
      const float x1 = (cmd.ClipRect.z - clip_off.x) * clip_scale.x;
      const float y1 = (cmd.ClipRect.w - clip_off.y) * clip_scale.y;
      if (x1 <= x0 || y1 <= y0) continue;
      // GL scissor origin is bottom-left.
      scissor_(static_cast<GLint>(x0), static_cast<GLint>(fb_h - y1), static_cast<GLsizei>(x1 - x0),
               static_cast<GLsizei>(y1 - y0));
      gl_.BindTexture(GL_TEXTURE_2D,
                      static_cast<GLuint>(reinterpret_cast<intptr_t>(cmd.GetTexID())));
      gl_.DrawElements(GL_TRIANGLES, static_cast<GLsizei>(cmd.ElemCount), kIndexType,
                       reinterpret_cast<void*>(cmd.IdxOffset * sizeof(ImDrawIdx)));
    }
  }
  gl_.Disable(GL_SCISSOR_TEST);
  gl_.BindVertexArray(0);
  gl_.check("imgui render");
}

}  // namespace dynscope::app::viewer
