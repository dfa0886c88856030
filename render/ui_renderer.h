// UiRenderer: draws 2D UI triangle lists (Dear ImGui's draw data, handed over as plain arrays)
// through our GL table, so the whole UI renders the same under OSMesa and GLFW.
#pragma once

#include <cstdint>
#include <vector>

#include "render/gl_functions.h"
#include "render/shader_program.h"

namespace dynscope::render {

class GlContext;

/// One vertex of a UI triangle list: pixel position, texture coordinate, RGBA8 colour (20 bytes,
/// the layout of ImDrawVert).
struct UiVertex {
  float x, y;
  float u, v;
  uint32_t rgba;
};

/// A run of triangles with one texture and one clip rectangle (pixels, origin top-left).
struct UiCommand {
  float clip_x0 = 0, clip_y0 = 0, clip_x1 = 0, clip_y1 = 0;
  uint64_t texture = 0;  ///< A texture id from UiRenderer::upload_texture.
  uint32_t index_offset = 0;
  uint32_t index_count = 0;
};

/// One list of triangles: vertices and indices (16 or 32 bit) are borrowed, not copied.
struct UiDrawList {
  const UiVertex* vertices = nullptr;
  int vertex_count = 0;
  const void* indices = nullptr;
  int index_count = 0;
  int index_size = 2;  ///< Bytes per index: 2 or 4.
  std::vector<UiCommand> commands;
};

/// Everything drawn over the 3D view in one frame, in list order.
struct UiDrawData {
  float display_x = 0, display_y = 0;           ///< Top-left of the display (pixels).
  float display_width = 0, display_height = 0;  ///< Display size (pixels).
  float scale_x = 1, scale_y = 1;               ///< Framebuffer pixels per display pixel.
  std::vector<UiDrawList> lists;
};

/// Draws UiDrawData into the current context's default framebuffer with the embedded
/// imgui.vert/imgui.frag pair, streamed vertex/index buffers and scissor rectangles.
class UiRenderer {
 public:
  /// Loads GL from `context` (made current) and compiles the shaders. Throws Error on GL failure.
  explicit UiRenderer(GlContext& context);
  ~UiRenderer();
  UiRenderer(const UiRenderer&) = delete;
  UiRenderer& operator=(const UiRenderer&) = delete;

  /// Uploads an RGBA8 image `[height,width,4]` (e.g. a font atlas); returns its texture id.
  uint64_t upload_texture(const uint8_t* rgba, int width, int height);
  /// Replaces the pixels of `texture` (an id from upload_texture) with an RGBA8 image
  /// `[height,width,4]`, reallocating it when the size changed. Throws ValueError for an id this
  /// renderer did not create.
  void update_texture(uint64_t texture, const uint8_t* rgba, int width, int height);
  /// Draws `data` over what the framebuffer holds; alpha stays opaque.
  void render(const UiDrawData& data);

 private:
  GlFunctions gl_;
  ShaderProgram program_;
  struct TextureSize {
    GLuint id;
    int width, height;
  };
  std::vector<TextureSize> textures_;
  GLuint vao_ = 0, vbo_ = 0, ibo_ = 0;
};

}  // namespace dynscope::render
