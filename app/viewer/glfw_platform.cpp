// GlfwPlatform: GLFW events → ImGui IO via imgui_impl_glfw (from Debian's libimgui.a).
#include "app/viewer/glfw_platform.h"

#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <imgui.h>

#include "engine/core/error.h"
#include "render/glfw_context.h"

namespace dynscope::app::viewer {

GlfwPlatform::GlfwPlatform(render::GlfwContext& context) : context_(context) {
  if (!ImGui_ImplGlfw_InitForOpenGL(context_.window(), true)) {
    throw Error("viewer: ImGui's GLFW backend failed to initialise");
  }
}

GlfwPlatform::~GlfwPlatform() { ImGui_ImplGlfw_Shutdown(); }

void GlfwPlatform::new_frame() {
  glfwPollEvents();
  ImGui_ImplGlfw_NewFrame();
}

bool GlfwPlatform::should_close() const { return glfwWindowShouldClose(context_.window()) != 0; }

}  // namespace dynscope::app::viewer
