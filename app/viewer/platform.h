// Viewer platform layer: where ImGui's display size, time and input come from (window or none).
#pragma once

namespace dynscope::app::viewer {

/// Owns the process's ImGui context for the viewer's lifetime: created with no .ini file (the
/// layout is fixed, so screenshots are reproducible) and the viewer's style.
class ImGuiSession {
 public:
  ImGuiSession();
  ~ImGuiSession();
  ImGuiSession(const ImGuiSession&) = delete;
  ImGuiSession& operator=(const ImGuiSession&) = delete;
};

/// Feeds ImGui one frame of platform state. Implementations: GlfwPlatform (a real window and its
/// input) and NullPlatform (fixed size, synthetic input, for headless screenshots and tests).
class Platform {
 public:
  virtual ~Platform() = default;
  /// Fills ImGui's IO (display size in pixels, time step in seconds, mouse, keys) for the next
  /// ImGui::NewFrame.
  virtual void new_frame() = 0;
  /// True once the user asked to close the window (never for the null platform).
  virtual bool should_close() const = 0;
};

}  // namespace dynscope::app::viewer
