// `dynscope render SCENE.h5|ROLLOUT.h5 --out DIR [--view] [--frames] [--size]` (headless).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "app/cli_util.h"
#include "app/commands.h"
#include "app/explain_run.h"
#include "engine/core/error.h"
#include "engine/core/log.h"
#include "engine/io/rollout_file.h"
#include "engine/io/scene_file.h"
#include "engine/io/temp_file.h"
#include "engine/io/trace_file.h"
#include "render/batch_render.h"
#include "render/context_factory.h"

namespace dynscope::app {
namespace {

// Largest multisampling count accepted (GL implementations offer at most a few dozen).
constexpr int kMaxSamples = 64;
// Deepest U-Net level a model can have (ModelConfig allows 1..8 levels).
constexpr int kMaxLevel = 7;

// True if `name` is one of the files render writes into its output directory.
bool is_render_output_name(const std::string& name) {
  if (name == "contact_sheet.png" || name == "render.mp4" || name == "view.json" ||
      name == "trace.h5") {
    return true;
  }
  const std::string prefix = "frame_", suffix = ".png";
  if (name.size() <= prefix.size() + suffix.size() || name.compare(0, prefix.size(), prefix) ||
      name.compare(name.size() - suffix.size(), suffix.size(), suffix)) {
    return false;
  }
  const std::string digits =
      name.substr(prefix.size(), name.size() - prefix.size() - suffix.size());
  return std::all_of(digits.begin(), digits.end(), [](unsigned char c) { return std::isdigit(c); });
}

// Refuses an --out that is an input, or that holds an input under the name of an output.
void require_outputs_distinct(const render::BatchRenderOptions& o, const std::string& checkpoint) {
  namespace fs = std::filesystem;
  const std::vector<NamedPath> inputs = {{"input", o.scene_path},
                                         {"--view", o.view_path},
                                         {"--trace", o.trace_path},
                                         {"--checkpoint", checkpoint}};
  require_distinct_output("--out", o.out_dir, inputs);
  for (const auto& [option, path] : inputs) {
    if (path.empty()) continue;
    const fs::path p(path);
    if (is_render_output_name(p.filename().string()) &&
        same_file(p.parent_path().empty() ? "." : p.parent_path().string(), o.out_dir)) {
      throw ValueError("--out", "the " + option + " file '" + path +
                                    "' is in the output directory under the name of an output; "
                                    "rendering would overwrite it (choose another --out)");
    }
  }
}

// Refuses a --level or --pick the trace does not have (the model's hierarchy decides).
void require_trace_selection(const ModelTrace& trace, const render::BatchRenderOptions& o,
                             const std::string& source) {
  const int levels = static_cast<int>(trace.levels.size());
  if (o.level >= levels) {
    throw ValueError("--level", "must be in [0, " + std::to_string(levels - 1) + "] (the levels " +
                                    "of " + source + "), got " + std::to_string(o.level));
  }
  if (o.picked_point < 0) return;
  const int level = std::max(o.level, 0);
  const auto points = static_cast<int64_t>(trace.levels[static_cast<size_t>(level)].points.rows());
  if (o.picked_point >= points) {
    throw ValueError("--pick", "must be in [0, " + std::to_string(points - 1) + "] (the points " +
                                   "of level " + std::to_string(level) + " in " + source +
                                   "), got " + std::to_string(o.picked_point));
  }
}

// --explain: explains the rollout's divergence (or the chosen frame, object or point) and draws
// the pass's frame with every point coloured by its share.
void prepare_explanation(render::BatchRenderOptions& options, const std::string& checkpoint,
                         const std::string& object, int point, const std::string& target) {
  if (checkpoint.empty())
    throw ValueError("--explain", "needs --checkpoint (the model to explain)");
  if (!options.trace_path.empty()) throw ValueError("--explain", "give --trace or --explain");
  require_readable_file(options.scene_path);
  if (!is_rollout_file(options.scene_path)) {
    throw ValueError("--explain", "explains a rollout: " + options.scene_path + " is a scene file");
  }
  ExplainRequest request;
  request.checkpoint = checkpoint;
  request.rollout_path = options.scene_path;
  request.object = object;
  request.point = point;
  request.target = parse_explain_target(target);
  if (!options.frames.empty()) {
    const auto [first, last] =
        render::parse_frame_range(options.frames, read_rollout(options.scene_path).num_frames());
    if (first != last) throw ValueError("--frames", "with --explain give one frame (one pass)");
    request.frame = first;
  }
  const ExplainRun run = explain_checkpoint_rollout(request);
  const Explanation& e = run.explanation;
  options.frames = std::to_string(e.frame);
  auto attribution = std::make_shared<render::PointAttribution>();
  attribution->shares.assign(e.point_shares.begin(), e.point_shares.end());
  attribution->explained = e.points;
  options.attribution = attribution;
  char line[256];
  std::snprintf(line, sizeof(line), "explained: %s, pass %d -> frame %d, error %.4g (%+.4g)",
                explained_subject(e, run.names).c_str(), e.frame, e.frame + 1, e.error,
                e.error_growth);
  std::vector<std::string>& legend = options.attribution_legend;
  legend = {line, "colour: share of |grad x input| (grey: < 1 % of the largest); halo: explained"};
  const std::vector<std::string> lines = contributor_lines(e, run.names, 5);
  legend.insert(legend.end(), lines.begin(), lines.end());
  for (const std::string& l : legend) std::printf("%s\n", l.c_str());
}

}  // namespace

void add_render_command(CLI::App& app) {
  auto options = std::make_shared<render::BatchRenderOptions>();
  auto size = std::make_shared<std::string>();
  auto backend = std::make_shared<std::string>("osmesa");
  auto checkpoint = std::make_shared<std::string>();
  auto explain = std::make_shared<bool>(false);
  auto explain_object = std::make_shared<std::string>();
  auto explain_point = std::make_shared<int>(-1);
  auto explain_target = std::make_shared<std::string>("error");
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
      "as neighbour colour. Without either, they are the model's hierarchy at each rendered\n"
      "frame as the scenario's preset builds it (the same lists, no filter weights; mesh input\n"
      "when the view shows interaction points).\n"
      "With a rollout, --checkpoint and --explain it draws the pass `dynscope explain` picks\n"
      "(the divergence, or --frames T / --object / --point) with every point coloured by its\n"
      "share of the attribution and the explained points under a halo.");
  cmd->add_option("input", options->scene_path, "SCENE.h5|ROLLOUT.h5: scene or rollout file (HDF5)")
      ->required();
  cmd->add_option("--view", options->view_path, "View spec JSON (camera, layers, colormap, ...)");
  cmd->add_option("--frames", options->frames,
                  "Frames a:b (a .. b-1), a:, :b or a single frame; negative counts from the end");
  cmd->add_option("--trace", options->trace_path,
                  "Model trace of the scene (`dynscope trace`): draw the model's levels and lists");
  cmd->add_option(
      "--checkpoint", *checkpoint,
      "Trace this checkpoint at the frame (--frames N, default 2) and draw like --trace");
  auto given = std::make_shared<std::vector<std::string>>();
  auto mark = [given](const char* name) {
    return [given, name](const std::string&) { given->push_back(name); };
  };
  cmd->add_option("--level", options->level, "Show this U-Net level's points (0 = input points)")
      ->each(mark("--level"));
  cmd->add_option("--pick", options->picked_point,
                  "Show the neighbourhoods of this point of the level (its index there)")
      ->each(mark("--pick"));
  cmd->add_flag("--explain", *explain,
                "Rollouts with --checkpoint: colour the points by what made the prediction go "
                "wrong (see `dynscope explain`)");
  cmd->add_option("--object", *explain_object, "With --explain: the object (name or id)");
  cmd->add_option("--point", *explain_point, "With --explain: one rollout point instead")
      ->check(unsigned_integer());
  cmd->add_option("--target", *explain_target, "With --explain: error or acceleration")
      ->capture_default_str();
  cmd->add_option("--size", *size, "Image size WxH, overriding the view (e.g. 1280x720)");
  cmd->add_option("--out", options->out_dir, "Output directory")->required();
  cmd->add_option("--context", *backend, "GL context: osmesa (headless) or glfw (hidden window)")
      ->capture_default_str();
  cmd->add_option("--samples", options->samples, "Multisampling (anti-aliasing) samples")
      ->capture_default_str();
  cmd->add_flag(
      "--no-video", [options](int64_t) { options->video = false; }, "Skip the MP4");
  cmd->callback([options, size, backend, checkpoint, given, explain, explain_object, explain_point,
                 explain_target] {
    auto was_given = [&](const char* name) {
      return std::find(given->begin(), given->end(), name) != given->end();
    };
    if (was_given("--level")) require_int_in_range("--level", options->level, 0, kMaxLevel);
    if (was_given("--pick")) {
      require_int_in_range("--pick", options->picked_point, 0, std::numeric_limits<int32_t>::max());
    }
    require_int_in_range("--samples", options->samples, 0, kMaxSamples, "(0: no multisampling)");
    require_outputs_distinct(*options, *checkpoint);
    if (!options->trace_path.empty()) {
      require_readable_file(options->trace_path);
      require_readable_file(options->scene_path);
      const ModelTrace trace = read_trace(options->trace_path);
      require_trace_selection(trace, *options, options->trace_path);
      if (!is_rollout_file(options->scene_path)) {
        check_trace_matches_scene(trace, read_scene(options->scene_path), options->trace_path);
      }
    }
    if (!size->empty()) {
      const auto [w, h] = render::parse_image_size(*size);
      options->width = w;
      options->height = h;
    }
    if (!*explain && (!explain_object->empty() || *explain_point >= 0)) {
      throw ValueError(explain_object->empty() ? "--point" : "--object", "needs --explain");
    }
    std::unique_ptr<TempFile> trace_file;
    if (*explain) {
      prepare_explanation(*options, *checkpoint, *explain_object, *explain_point, *explain_target);
    } else if (!checkpoint->empty()) {
      if (!options->trace_path.empty()) {
        throw ValueError("--checkpoint", "give --checkpoint or --trace, not both");
      }
      if (is_rollout_file(options->scene_path)) {
        throw ValueError("--checkpoint",
                         "traces are drawn over scene files; over a rollout, add --explain");
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
      require_trace_selection(trace, *options, *checkpoint);
      std::filesystem::create_directories(options->out_dir);
      // Rendered from a temporary file that replaces DIR/trace.h5 only once rendering succeeded.
      trace_file = std::make_unique<TempFile>(
          (std::filesystem::path(options->out_dir) / "trace.h5").string());
      options->trace_path = trace_file->path();
      write_trace(trace, options->trace_path);
      log_info("traced ", *checkpoint, " at frame ", frame);
    }
    auto context = render::create_context(*backend, 64, 64);
    const render::BatchRenderResult result = render::render_file(*context, *options);
    if (trace_file) {
      trace_file->commit();
      std::printf("trace: %s\n",
                  (std::filesystem::path(options->out_dir) / "trace.h5").string().c_str());
    }
    for (const std::string& note : result.notes) log_info(note);
    std::printf("wrote %zu frames to %s\n", result.frame_files.size(), options->out_dir.c_str());
    if (!result.contact_sheet.empty())
      std::printf("contact sheet: %s\n", result.contact_sheet.c_str());
    if (!result.video.empty()) std::printf("video: %s\n", result.video.c_str());
    std::printf("view: %s\n", result.view_file.c_str());
  });
}

}  // namespace dynscope::app
