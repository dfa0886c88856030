// ImGuiRenderer: hands Dear ImGui's draw data to render's UiRenderer as plain triangle lists (no
// GL here), so the UI draws the same under OSMesa and GLFW.
#pragma once

#include <memory>

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

 private:
  render::UiRenderer ui_;
};

}  // namespace dynscope::app::viewer
