// UI triangle lists → GL through render's function table (see ui_renderer.h).
#include "render/ui_renderer.h"

#include <cstddef>
#include <string>

#include "engine/core/error.h"
#include "render/gl_context.h"

namespace dynscope::render {

static_assert(sizeof(UiVertex) == 20, "UiVertex must match the 20-byte UI vertex layout");

UiRenderer::UiRenderer(GlContext& context) {
  context.make_current();
  gl_.load(context);
  program_ = ShaderProgram::from_embedded(gl_, "imgui.vert", "imgui.frag");
  gl_.GenVertexArrays(1, &vao_);
  gl_.GenBuffers(1, &vbo_);
  gl_.GenBuffers(1, &ibo_);
  gl_.BindVertexArray(vao_);
  gl_.BindBuffer(GL_ARRAY_BUFFER, vbo_);
  gl_.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, ibo_);
  const GLsizei stride = sizeof(UiVertex);
  gl_.EnableVertexAttribArray(0);
  gl_.VertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, stride,
                          reinterpret_cast<void*>(offsetof(UiVertex, x)));
  gl_.EnableVertexAttribArray(1);
  gl_.VertexAttribPointer(1, 2, GL_FLOAT, GL_FALSE, stride,
                          reinterpret_cast<void*>(offsetof(UiVertex, u)));
  gl_.EnableVertexAttribArray(2);
  gl_.VertexAttribPointer(2, 4, GL_UNSIGNED_BYTE, GL_TRUE, stride,
                          reinterpret_cast<void*>(offsetof(UiVertex, rgba)));
  gl_.BindVertexArray(0);
  gl_.check("ui renderer setup");
}

UiRenderer::~UiRenderer() {
  for (const TextureSize& t : textures_) gl_.DeleteTextures(1, &t.id);
  gl_.DeleteBuffers(1, &vbo_);
  gl_.DeleteBuffers(1, &ibo_);
  gl_.DeleteVertexArrays(1, &vao_);
}

uint64_t UiRenderer::upload_texture(const uint8_t* rgba, int width, int height) {
  GLuint texture = 0;
  gl_.GenTextures(1, &texture);
  gl_.BindTexture(GL_TEXTURE_2D, texture);
  gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  gl_.PixelStorei(GL_UNPACK_ALIGNMENT, 1);
  gl_.TexImage2D(GL_TEXTURE_2D, 0, GL_RGBA, width, height, 0, GL_RGBA, GL_UNSIGNED_BYTE, rgba);
  gl_.check("ui texture upload");
  textures_.push_back({texture, width, height});
  return texture;
}

void UiRenderer::update_texture(uint64_t texture, const uint8_t* rgba, int width, int height) {
  for (TextureSize& t : textures_) {
    if (t.id != texture) continue;
    gl_.BindTexture(GL_TEXTURE_2D, t.id);
    gl_.PixelStorei(GL_UNPACK_ALIGNMENT, 1);
    if (t.width == width && t.height == height) {
      gl_.TexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, rgba);
    } else {
      gl_.TexImage2D(GL_TEXTURE_2D, 0, GL_RGBA, width, height, 0, GL_RGBA, GL_UNSIGNED_BYTE, rgba);
      t.width = width;
      t.height = height;
    }
    gl_.check("ui texture update");
    return;
  }
  throw ValueError("texture", "not a texture of this UI renderer: " + std::to_string(texture));
}

void UiRenderer::render(const UiDrawData& data) {
  const float fb_w = data.display_width * data.scale_x;
  const float fb_h = data.display_height * data.scale_y;
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
  program_.set("u_display_pos", data.display_x, data.display_y);
  program_.set("u_display_size", data.display_width, data.display_height);
  program_.set("u_texture", 0);
  gl_.ActiveTexture(GL_TEXTURE0);
  gl_.BindVertexArray(vao_);
  gl_.BindBuffer(GL_ARRAY_BUFFER, vbo_);
  gl_.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, ibo_);
  for (const UiDrawList& list : data.lists) {
    const GLenum index_type = list.index_size == 2 ? GL_UNSIGNED_SHORT : GL_UNSIGNED_INT;
    gl_.BufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(list.vertex_count) * sizeof(UiVertex),
                   list.vertices, GL_STREAM_DRAW);
    gl_.BufferData(GL_ELEMENT_ARRAY_BUFFER,
                   static_cast<GLsizeiptr>(list.index_count) * list.index_size, list.indices,
                   GL_STREAM_DRAW);
    for (const UiCommand& cmd : list.commands) {
      const float x0 = (cmd.clip_x0 - data.display_x) * data.scale_x;
      const float y0 = (cmd.clip_y0 - data.display_y) * data.scale_y;
      const float x1 = (cmd.clip_x1 - data.display_x) * data.scale_x;
      const float y1 = (cmd.clip_y1 - data.display_y) * data.scale_y;
      if (x1 <= x0 || y1 <= y0) continue;
      // GL scissor origin is bottom-left.
      gl_.Scissor(static_cast<GLint>(x0), static_cast<GLint>(fb_h - y1),
                  static_cast<GLsizei>(x1 - x0), static_cast<GLsizei>(y1 - y0));
      gl_.BindTexture(GL_TEXTURE_2D, static_cast<GLuint>(cmd.texture));
      gl_.DrawElements(
          GL_TRIANGLES, static_cast<GLsizei>(cmd.index_count), index_type,
          reinterpret_cast<void*>(static_cast<uintptr_t>(cmd.index_offset) * list.index_size));
    }
  }
  gl_.Disable(GL_SCISSOR_TEST);
  gl_.BindVertexArray(0);
  gl_.check("ui render");
}

}  // namespace dynscope::render
