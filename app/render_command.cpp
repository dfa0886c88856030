// `dynscope render SCENE.h5|ROLLOUT.h5 --out DIR [--view] [--frames] [--size]` (headless).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>

#include "app/commands.h"
#include "engine/core/log.h"
#include "render/batch_render.h"
#include "render/context_factory.h"

namespace dynscope::app {

void add_render_command(CLI::App& app) {
  auto options = std::make_shared<render::BatchRenderOptions>();
  auto size = std::make_shared<std::string>();
  auto backend = std::make_shared<std::string>("osmesa");
  CLI::App* cmd = app.add_subcommand(
      "render",
      "Render the frames of a scene or a rollout off-screen (OSMesa, no display needed): one PNG "
      "per frame, a contact sheet and, when ffmpeg is on PATH, an MP4. A rollout is drawn as its "
      "prediction coloured by error with the ground truth translucent. The resolved view is saved "
      "as DIR/view.json.");
  cmd->add_option("input", options->scene_path, "SCENE.h5|ROLLOUT.h5: scene or rollout file (HDF5)")
      ->required();
  cmd->add_option("--view", options->view_path, "View spec JSON (camera, layers, colormap, ...)");
  cmd->add_option("--frames", options->frames,
                  "Frames a:b (a .. b-1), a:, :b or a single frame; negative counts from the end");
  cmd->add_option("--size", *size, "Image size WxH, overriding the view (e.g. 1280x720)");
  cmd->add_option("--out", options->out_dir, "Output directory")->required();
  cmd->add_option("--context", *backend, "GL context: osmesa (headless) or glfw (hidden window)")
      ->capture_default_str();
  cmd->add_option("--samples", options->samples, "Multisampling (anti-aliasing) samples")
      ->capture_default_str();
  cmd->add_flag(
      "--no-video", [options](int64_t) { options->video = false; }, "Skip the MP4");
  cmd->callback([options, size, backend] {
    if (!size->empty()) {
      const auto [w, h] = render::parse_image_size(*size);
      options->width = w;
      options->height = h;
    }
    auto context = render::create_context(*backend, 64, 64);
    const render::BatchRenderResult result = render::render_file(*context, *options);
    for (const std::string& note : result.notes) log_info(note);
    std::printf("wrote %zu frames to %s\n", result.frame_files.size(), options->out_dir.c_str());
    if (!result.contact_sheet.empty())
      std::printf("contact sheet: %s\n", result.contact_sheet.c_str());
    if (!result.video.empty()) std::printf("video: %s\n", result.video.c_str());
    std::printf("view: %s\n", result.view_file.c_str());
  });
}

}  // namespace dynscope::app
