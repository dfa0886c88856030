// ImGuiRenderer: hands Dear ImGui's draw data to render's UiRenderer as plain triangle lists (no
// GL here), so the UI draws the same under OSMesa and GLFW.
#pragma once

#include <memory>

#include "render/image.h"
#include "render/ui_renderer.h"

struct ImDrawData;

namespace dynscope::render {
class GlContext;
}

namespace dynscope::app::viewer {

/// Owns a render::UiRenderer and the font atlas texture of the current ImGui context. ImGui's own
/// OpenGL3 backend loads GL through libGL and fails under OSMesa; this one goes through render/.
class ImGuiRenderer {
 public:
  /// Uploads the font atlas of the current ImGui context (ImGui::CreateContext must have run) and
  /// registers it as the atlas's texture id. Throws Error on GL failure.
  explicit ImGuiRenderer(render::GlContext& context);
  ~ImGuiRenderer();
  ImGuiRenderer(const ImGuiRenderer&) = delete;
  ImGuiRenderer& operator=(const ImGuiRenderer&) = delete;

  /// Draws `data` (from ImGui::GetDrawData) over what the framebuffer holds.
  void render(const ImDrawData* data);
  /// Shows `image` (RGBA8, rows top to bottom) through one texture kept for it and returns that
  /// texture's ImGui id (e.g. for ImDrawList::AddImage); later calls replace its pixels.
  void* show_image(const render::Image& image);

 private:
  render::UiRenderer ui_;
  uint64_t image_texture_ = 0;  // 0: not created yet
};

}  // namespace dynscope::app::viewer
