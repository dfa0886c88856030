// GLFW context: a desktop window with a GL 3.3+ core-profile context (interactive viewer).
#pragma once

#include <string>

#include "render/gl_context.h"

struct GLFWwindow;

namespace dynscope::render {

/// Window-backed GL context. Include only where a program picks its context.
class GlfwContext : public GlContext {
 public:
  /// Opens a window of width x height pixels titled `title` (hidden if !visible) with a core
  /// profile context and makes it current. Throws Error with GLFW's reason (e.g. no DISPLAY).
  GlfwContext(int width, int height, const std::string& title, bool visible = true);
  ~GlfwContext() override;
  GlfwContext(const GlfwContext&) = delete;
  GlfwContext& operator=(const GlfwContext&) = delete;

  void make_current() override;
  int width() const override;
  int height() const override;
  void resize(int width, int height) override;
  void swap_buffers() override;
  void* get_proc_address(const char* name) override;
  std::string backend() const override { return "glfw"; }

  /// The GLFW window, for input handling by the viewer.
  GLFWwindow* window() const { return window_; }

 private:
  GLFWwindow* window_ = nullptr;
};

}  // namespace dynscope::render
