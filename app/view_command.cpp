// `dynscope view [SCENE|ROLLOUT|TRACE.h5] [--checkpoint A.pt [--compare B.pt]] [--trace TRACE.h5]
// [--view VIEW.json] [--screenshot OUT.png] [--size WxH] [--view-thread auto|on|off]`: the viewer,
// with the model behind it.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <thread>

#include "app/cli_util.h"
#include "app/commands.h"
#include "app/viewer/engine_model_services.h"
#include "app/viewer/glfw_platform.h"
#include "app/viewer/model_services.h"
#include "app/viewer/null_platform.h"
#include "app/viewer/platform.h"
#include "app/viewer/viewer_app.h"
#include "engine/core/error.h"
#include "engine/core/log.h"
#include "engine/io/temp_file.h"
#include "render/batch_render.h"
#include "render/context_factory.h"
#include "render/gl_functions.h"
#include "render/glfw_context.h"
#include "render/image.h"

namespace dynscope::app {
namespace {

// Most frames drawn before a screenshot (each takes a fraction of a second headless).
constexpr int kMaxWarmupFrames = 10000;

struct ViewOptions {
  std::string scene_path;
  std::string checkpoint;
  std::string compare;
  std::string trace_path;
  std::string view_path;
  std::string screenshot;
  std::string size;
  int warmup_frames = 3;
  std::string view_thread = "auto";
};

// Whether the GL driver behind `context` rasterises in software (llvmpipe, softpipe, swrast):
// its vertex stage then runs on the thread that draws.
bool software_renderer(const std::string& gl_description) {
  for (const char* software : {"llvmpipe", "softpipe", "swrast"}) {
    if (gl_description.find(software) != std::string::npos) return true;
  }
  return false;
}

// --view-thread: "on", "off", or "auto" (on for a window on a software rasteriser, where the 3D
// view would otherwise hold up the UI thread; off with a GPU, whose draw calls return at once,
// and for a screenshot, which is one image).
void apply_view_thread(viewer::ViewerApp& app, render::GlContext& context, const ViewOptions& o,
                       bool window) {
  render::GlFunctions gl;
  gl.load(context);
  const std::string driver = gl.describe();
  const bool on =
      o.view_thread == "on" || (o.view_thread == "auto" && window && software_renderer(driver));
  if (!on) return;
  app.set_view_thread(true);
  log_info("view: the 3D view is drawn on its own thread (", driver,
           "); --view-thread off draws it on the UI thread");
}

void load_inputs(viewer::ViewerApp& app, const ViewOptions& o) {
  if (!o.scene_path.empty()) app.state().open_file(o.scene_path);
  if (!o.trace_path.empty()) app.state().open_trace(o.trace_path);
  if (!o.checkpoint.empty()) {
    require_readable_file(o.checkpoint);
    app.state().set_checkpoint(o.checkpoint);
  }
  if (!o.compare.empty()) {
    require_readable_file(o.compare);
    app.state().start_rollouts(o.compare);
  }
  if (!o.view_path.empty()) app.state().open_view(o.view_path);
}

void run_headless(const ViewOptions& o, int width, int height) {
  auto context = render::create_context("osmesa", width, height);
  viewer::ImGuiSession session;
  viewer::NullPlatform platform(width, height);
  viewer::EngineModelServices services;
  viewer::ViewerApp app(*context, platform, &services);
  apply_view_thread(app, *context, o, false);
  load_inputs(app, o);
  // ImGui lays windows out over the first frames (auto-sized tables, popups); draw a few, and
  // wait for rollouts and traces so the picture shows their results.
  for (int i = 0; i < o.warmup_frames || app.state().busy(); ++i) {
    app.frame();
    if (app.state().busy()) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  // The picture goes to a temporary file that replaces --screenshot only when the viewer had no
  // error: a failed run leaves an existing PNG as it was.
  TempFile screenshot(o.screenshot);
  app.request_screenshot(screenshot.path());
  app.frame();
  if (!app.last_error().empty()) throw Error("view: " + app.last_error());
  screenshot.commit();
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
  viewer::EngineModelServices services;
  viewer::ViewerApp app(*context, platform, &services);
  apply_view_thread(app, *context, o, true);
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
      "object table, contact timeline, rollouts (truth vs prediction, error over time), the "
      "model's own levels and filter weights (--checkpoint, --trace), two checkpoints side by "
      "side (--compare) and what-if edits of the initial state. With --screenshot the whole UI "
      "is rendered off-screen (OSMesa, no display needed) to a PNG and the program exits.");
  cmd->add_option("file", o->scene_path, "Scene, rollout or trace file (HDF5) to open");
  cmd->add_option("--checkpoint", o->checkpoint,
                  "Checkpoint whose traces drive the level browser and inspector; what-if and "
                  "rollouts run it");
  cmd->add_option("--compare", o->compare,
                  "Second checkpoint: roll both out on the scene and show them side by side")
      ->needs("--checkpoint");
  cmd->add_option("--trace", o->trace_path,
                  "Trace file (`dynscope trace`) for levels and inspector");
  cmd->add_option("--view", o->view_path, "View spec JSON (as saved by the viewer or render)");
  cmd->add_option("--screenshot", o->screenshot, "Render the UI headless to this PNG and exit");
  cmd->add_option("--size", o->size, "Window / screenshot size WxH (default 1280x800)");
  cmd->add_option("--warmup", o->warmup_frames, "Frames drawn before the screenshot")
      ->capture_default_str();
  cmd->add_option("--view-thread", o->view_thread,
                  "Draw the 3D view on its own thread and off-screen context (on), on the UI "
                  "thread (off), or auto: on for a window on a software rasteriser (llvmpipe), "
                  "where drawing large clouds would otherwise slow the panels down; the view "
                  "then shows the newest finished image")
      ->check(CLI::IsMember({"auto", "on", "off"}))
      ->capture_default_str();
  cmd->callback([o] {
    int width = 1280, height = 800;
    if (!o->size.empty()) std::tie(width, height) = render::parse_image_size(o->size);
    render::check_image_size("--size", width, height);
    require_int_in_range("--warmup", o->warmup_frames, 0, kMaxWarmupFrames);
    require_output_directory("--screenshot", o->screenshot);
    require_distinct_output("--screenshot", o->screenshot,
                            {{"file", o->scene_path},
                             {"--checkpoint", o->checkpoint},
                             {"--compare", o->compare},
                             {"--trace", o->trace_path},
                             {"--view", o->view_path}});
    if (!o->screenshot.empty()) {
      run_headless(*o, width, height);
    } else {
      run_window(*o, width, height);
    }
  });
}

}  // namespace dynscope::app
