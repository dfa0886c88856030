// `dynscope render SCENE.h5|ROLLOUT.h5 --out DIR [--view] [--frames] [--size]` (headless).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "app/cli_util.h"
#include "app/commands.h"
#include "engine/core/error.h"
#include "engine/core/log.h"
#include "engine/io/rollout_file.h"
#include "engine/io/scene_file.h"
#include "engine/io/trace_file.h"
#include "render/batch_render.h"
#include "render/context_factory.h"

namespace dynscope::app {

void add_render_command(CLI::App& app) {
  auto options = std::make_shared<render::BatchRenderOptions>();
  auto size = std::make_shared<std::string>();
  auto backend = std::make_shared<std::string>("osmesa");
  auto checkpoint = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand(
      "render",
      "Render the frames of a scene or a rollout off-screen (OSMesa, no display needed): one PNG "
      "per frame, a contact sheet and, when ffmpeg is on PATH, an MP4. A rollout is drawn as its "
      "prediction coloured by error with the ground truth translucent. The resolved view is saved "
      "as DIR/view.json.\n"
      "U-Net levels and neighbourhoods: with --trace (a `dynscope trace` file) or --checkpoint\n"
      "(one forward pass is traced at the frame, saved as DIR/trace.h5) they are the model's\n"
      "own: level points, voxels, object kNN and relational lists of --pick at --level, the\n"
      "level-below points pooled into it and fed by it, and the learned filter |h(p_k - p_0)|\n"
      "as neighbour colour. Without either, levels are a rest-frame preview.");
  cmd->add_option("input", options->scene_path, "SCENE.h5|ROLLOUT.h5: scene or rollout file (HDF5)")
      ->required();
  cmd->add_option("--view", options->view_path, "View spec JSON (camera, layers, colormap, ...)");
  cmd->add_option("--frames", options->frames,
                  "Frames a:b (a .. b-1), a:, :b or a single frame; negative counts from the end");
  cmd->add_option("--trace", options->trace_path,
                  "Model trace of the scene (`dynscope trace`): draw the model's levels and lists");
  cmd->add_option("--checkpoint", *checkpoint,
                  "Trace this checkpoint at the frame (--frames N, default 2) and draw like --trace");
  cmd->add_option("--level", options->level, "Show this U-Net level's points (0 = input points)");
  cmd->add_option("--pick", options->picked_point,
                  "Show the neighbourhoods of this point of the level (its index there)");
  cmd->add_option("--size", *size, "Image size WxH, overriding the view (e.g. 1280x720)");
  cmd->add_option("--out", options->out_dir, "Output directory")->required();
  cmd->add_option("--context", *backend, "GL context: osmesa (headless) or glfw (hidden window)")
      ->capture_default_str();
  cmd->add_option("--samples", options->samples, "Multisampling (anti-aliasing) samples")
      ->capture_default_str();
  cmd->add_flag(
      "--no-video", [options](int64_t) { options->video = false; }, "Skip the MP4");
  cmd->callback([options, size, backend, checkpoint] {
    if (!size->empty()) {
      const auto [w, h] = render::parse_image_size(*size);
      options->width = w;
      options->height = h;
    }
    if (!checkpoint->empty()) {
      if (!options->trace_path.empty()) {
        throw ValueError("--checkpoint", "give --checkpoint or --trace, not both");
      }
      if (is_rollout_file(options->scene_path)) {
        throw ValueError("--checkpoint", "traces are drawn over scene files, not rollouts");
      }
      require_readable_file(options->scene_path);
      const Scene scene = read_scene(options->scene_path);
      int frame = 2;
      if (!options->frames.empty()) {
        const auto [first, last] = render::parse_frame_range(options->frames, scene.num_frames());
        if (first != last) {
          throw ValueError("--frames", "with --checkpoint give one frame (one forward pass)");
        }
        frame = first;
      }
      options->frames = std::to_string(frame);
      const ModelTrace trace =
          capture_checkpoint_trace(*checkpoint, scene, options->scene_path, frame,
                                   std::max(options->level, 0), options->picked_point);
      std::filesystem::create_directories(options->out_dir);
      options->trace_path = (std::filesystem::path(options->out_dir) / "trace.h5").string();
      write_trace(trace, options->trace_path);
      log_info("traced ", *checkpoint, " at frame ", frame, ": ", options->trace_path);
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
