// NullPlatform: a fixed-size display with scripted input, so the viewer runs without a window.
#pragma once

#include <set>

#include "app/viewer/platform.h"

namespace dynscope::app::viewer {

/// Display of width x height pixels, 60 frames per second, input given by calls. Keys are ImGui's
/// ImGuiKey_ values (the key map is the identity), so tests name keys as ImGui does.
class NullPlatform : public Platform {
 public:
  /// Throws ValueError if a size is < 1.
  NullPlatform(int width, int height);

  void new_frame() override;
  bool should_close() const override { return false; }

  /// Moves the mouse to pixel (x, y) (origin top-left).
  void move_mouse(float x, float y);
  /// Presses (down) or releases mouse button 0 (left), 1 (right) or 2 (middle).
  void set_button(int button, bool down);
  /// Wheel steps for the next frame (positive: away from the user, zooms in).
  void scroll(float steps);
  /// Holds ImGuiKey `key` down during the next frame only (a key press).
  void press_key(int key);
  /// Text typed during the next frame.
  void type_text(const char* utf8);

 private:
  int width_, height_;
  float mouse_x_ = -1.0f, mouse_y_ = -1.0f;
  bool buttons_[3] = {false, false, false};
  float wheel_ = 0.0f;
  std::set<int> pressed_;
  std::set<int> released_next_;
  const char* text_ = nullptr;
};

}  // namespace dynscope::app::viewer
