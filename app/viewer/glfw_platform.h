// GlfwPlatform: real window input through ImGui's GLFW backend (input only; drawing is ours).
#pragma once

#include "app/viewer/platform.h"

namespace dynscope::render {
class GlfwContext;
}

namespace dynscope::app::viewer {

/// Input and display size of a GLFW window. Installs ImGui's GLFW callbacks on construction (an
/// ImGuiSession must exist) and removes them on destruction.
class GlfwPlatform : public Platform {
 public:
  explicit GlfwPlatform(render::GlfwContext& context);
  ~GlfwPlatform() override;
  GlfwPlatform(const GlfwPlatform&) = delete;
  GlfwPlatform& operator=(const GlfwPlatform&) = delete;

  /// Polls window events, then lets the backend fill ImGui's IO.
  void new_frame() override;
  bool should_close() const override;

 private:
  render::GlfwContext& context_;
};

}  // namespace dynscope::app::viewer
