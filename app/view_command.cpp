// `dynscope view [SCENE.h5] [--view VIEW.json] [--screenshot OUT.png] [--size WxH]`: the viewer.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>
#include <string>

#include "app/commands.h"
#include "app/viewer/glfw_platform.h"
#include "app/viewer/null_platform.h"
#include "app/viewer/platform.h"
#include "app/viewer/viewer_app.h"
#include "engine/core/error.h"
#include "render/batch_render.h"
#include "render/context_factory.h"
#include "render/glfw_context.h"

namespace dynscope::app {
namespace {

struct ViewOptions {
  std::string scene_path;
  std::string view_path;
  std::string screenshot;
  std::string size;
  int warmup_frames = 3;
};

void load_inputs(viewer::ViewerApp& app, const ViewOptions& o) {
  if (!o.scene_path.empty()) app.open_scene(o.scene_path);
  if (!o.view_path.empty()) app.open_view(o.view_path);
}

void run_headless(const ViewOptions& o, int width, int height) {
  auto context = render::create_context("osmesa", width, height);
  viewer::ImGuiSession session;
  viewer::NullPlatform platform(width, height);
  viewer::ViewerApp app(*context, platform);
  load_inputs(app, o);
  // ImGui lays windows out over the first frames (auto-sized tables, popups); draw a few.
  for (int i = 0; i < o.warmup_frames; ++i) app.frame();
  app.request_screenshot(o.screenshot);
  app.frame();
  if (!app.last_error().empty()) throw Error("view: " + app.last_error());
  std::printf("wrote %s (%dx%d)\n", o.screenshot.c_str(), width, height);
}

void run_window(const ViewOptions& o, int width, int height) {
  std::unique_ptr<render::GlfwContext> context;
  try {
    context = std::make_unique<render::GlfwContext>(width, height, "dynscope view", true);
  } catch (const std::exception& e) {
    throw Error(std::string("view: cannot open a window (") + e.what() +
                "); on a machine without a display use --screenshot OUT.png");
  }
  viewer::ImGuiSession session;
  viewer::GlfwPlatform platform(*context);
  viewer::ViewerApp app(*context, platform);
  // A bad file on the command line becomes the viewer's error popup, as it would from the UI.
  try {
    load_inputs(app, o);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "dynscope view: %s\n", e.what());
  }
  while (!platform.should_close()) app.frame();
}

}  // namespace

void add_view_command(CLI::App& app) {
  auto o = std::make_shared<ViewOptions>();
  CLI::App* cmd = app.add_subcommand(
      "view",
      "Interactive viewer: timeline, U-Net level browser, point picking with its neighbourhood, "
      "object table, contact timeline. With --screenshot the whole UI is rendered off-screen "
      "(OSMesa, no display needed) to a PNG and the program exits.");
  cmd->add_option("scene", o->scene_path, "Scene file (HDF5) to open");
  cmd->add_option("--view", o->view_path, "View spec JSON (as saved by the viewer or render)");
  cmd->add_option("--screenshot", o->screenshot, "Render the UI headless to this PNG and exit");
  cmd->add_option("--size", o->size, "Window / screenshot size WxH (default 1280x800)");
  cmd->add_option("--warmup", o->warmup_frames, "Frames drawn before the screenshot")
      ->capture_default_str();
  cmd->callback([o] {
    int width = 1280, height = 800;
    if (!o->size.empty()) std::tie(width, height) = render::parse_image_size(o->size);
    if (o->warmup_frames < 0) throw ValueError("--warmup", "must be >= 0");
    if (!o->screenshot.empty()) {
      run_headless(*o, width, height);
    } else {
      run_window(*o, width, height);
    }
  });
}

}  // namespace dynscope::app
