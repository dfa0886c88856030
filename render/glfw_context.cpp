// GLFW context: a window with a core-profile GL context; GL itself is reached via
// glfwGetProcAddress.
#include "render/glfw_context.h"

// GLFW must not pull in <GL/gl.h>: GL is reached through GlFunctions only.
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <mutex>

#include "engine/core/error.h"

namespace dynscope::render {
namespace {

std::mutex g_mutex;
int g_windows = 0;
std::string g_last_error;

void on_glfw_error(int code, const char* description) {
  g_last_error = std::string(description ? description : "unknown error") + " (GLFW error " +
                 std::to_string(code) + ")";
}

}  // namespace

GlfwContext::GlfwContext(int width, int height, const std::string& title, bool visible) {
  if (width < 1 || height < 1) {
    throw ValueError("window size", std::to_string(width) + "x" + std::to_string(height));
  }
  std::lock_guard<std::mutex> lock(g_mutex);
  glfwSetErrorCallback(on_glfw_error);
  if (g_windows == 0) {
    g_last_error.clear();
    if (!glfwInit()) {
      throw Error("glfw: cannot initialise: " +
                  (g_last_error.empty() ? std::string("no display?") : g_last_error));
    }
  }
  glfwDefaultWindowHints();
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_VISIBLE, visible ? GLFW_TRUE : GLFW_FALSE);
  glfwWindowHint(GLFW_DEPTH_BITS, 24);
  window_ = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
  if (!window_) {
    const std::string reason = g_last_error.empty() ? "unknown reason" : g_last_error;
    if (g_windows == 0) glfwTerminate();
    throw Error("glfw: cannot open a " + std::to_string(width) + "x" + std::to_string(height) +
                " window with a GL 3.3 core context: " + reason);
  }
  ++g_windows;
  glfwMakeContextCurrent(window_);
  glfwSwapInterval(1);
}

GlfwContext::~GlfwContext() {
  std::lock_guard<std::mutex> lock(g_mutex);
  glfwDestroyWindow(window_);
  if (--g_windows == 0) glfwTerminate();
}

void GlfwContext::make_current() { glfwMakeContextCurrent(window_); }

int GlfwContext::width() const {
  int w = 0, h = 0;
  glfwGetFramebufferSize(window_, &w, &h);
  return w;
}

int GlfwContext::height() const {
  int w = 0, h = 0;
  glfwGetFramebufferSize(window_, &w, &h);
  return h;
}

void GlfwContext::resize(int width, int height) {
  if (width < 1 || height < 1) {
    throw ValueError("window size", std::to_string(width) + "x" + std::to_string(height));
  }
  glfwSetWindowSize(window_, width, height);
}

void GlfwContext::swap_buffers() { glfwSwapBuffers(window_); }

void* GlfwContext::get_proc_address(const char* name) {
  return reinterpret_cast<void*>(glfwGetProcAddress(name));
}

}  // namespace dynscope::render
