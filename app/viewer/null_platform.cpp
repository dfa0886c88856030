// NullPlatform: scripted input for headless screenshots and tests.
#include "app/viewer/null_platform.h"

#include <imgui.h>

#include "engine/core/error.h"

namespace dynscope::app::viewer {

NullPlatform::NullPlatform(int width, int height) : width_(width), height_(height) {
  if (width < 1 || height < 1) {
    throw ValueError(
        "size", std::to_string(width) + "x" + std::to_string(height) + " must be at least 1x1");
  }
}

void NullPlatform::new_frame() {
  ImGuiIO& io = ImGui::GetIO();
  io.BackendPlatformName = "dynscope_null";
  for (int k = 0; k < ImGuiKey_COUNT; ++k) io.KeyMap[k] = k;
  io.DisplaySize = ImVec2(static_cast<float>(width_), static_cast<float>(height_));
  io.DisplayFramebufferScale = ImVec2(1.0f, 1.0f);
  io.DeltaTime = 1.0f / 60.0f;
  io.MousePos = ImVec2(mouse_x_, mouse_y_);
  for (int b = 0; b < 3; ++b) io.MouseDown[b] = buttons_[b];
  io.MouseWheel = wheel_;
  wheel_ = 0.0f;
  // A press is seen down for one frame and up on the next, as a real key tap would be.
  for (int k : released_next_) io.KeysDown[k] = false;
  released_next_.clear();
  for (int k : pressed_) {
    io.KeysDown[k] = true;
    released_next_.insert(k);
  }
  pressed_.clear();
  if (text_ != nullptr) io.AddInputCharactersUTF8(text_);
  text_ = nullptr;
}

void NullPlatform::move_mouse(float x, float y) {
  mouse_x_ = x;
  mouse_y_ = y;
}

void NullPlatform::set_button(int button, bool down) {
  if (button < 0 || button > 2) throw ValueError("button", std::to_string(button) + " is not 0..2");
  buttons_[button] = down;
}

void NullPlatform::scroll(float steps) { wheel_ += steps; }

void NullPlatform::press_key(int key) {
  if (key < 0 || key >= ImGuiKey_COUNT) throw ValueError("key", std::to_string(key));
  pressed_.insert(key);
}

void NullPlatform::type_text(const char* utf8) { text_ = utf8; }

}  // namespace dynscope::app::viewer
