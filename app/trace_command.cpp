// `dynscope trace`: record one forward pass (levels, neighbour lists, feature norms, filters).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>
#include <sstream>
#include <string>

#include "app/cli_util.h"
#include "app/commands.h"
#include "engine/core/error.h"
#include "engine/core/log.h"
#include "engine/io/rollout_file.h"
#include "engine/io/scene_file.h"
#include "engine/model/checkpoint_info.h"
#include "engine/rollout/trace_capture.h"
#include "engine/train/train_options.h"

namespace dynscope::app {
namespace {

struct TraceArgs {
  std::string checkpoint;
  std::string scene;
  std::string rollout;
  std::string out;
  int frame = 2;
  std::string query;
  double voxel = 0.0;
  bool voxel_given = false;
};

std::vector<int> parse_queries(const std::string& text) {
  std::vector<int> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    if (item.empty()) continue;
    try {
      size_t used = 0;
      const int v = std::stoi(item, &used);
      if (used != item.size() || v < 0) throw std::invalid_argument(item);
      out.push_back(v);
    } catch (const std::exception&) {
      throw ValueError("--query", "'" + item + "' is not a point index (an integer >= 0)");
    }
  }
  return out;
}

// The pass that produced frame t+1 of a rollout, from its own predicted frames.
void run_rollout_trace(const TraceArgs& args) {
  if (args.voxel_given) {
    throw ValueError("--voxel", "a rollout's points are fixed (it was sampled when rolled out)");
  }
  require_readable_file(args.checkpoint);
  require_readable_file(args.rollout);
  require_output_directory("--out", args.out);
  require_distinct_output("--out", args.out,
                          {{"--rollout", args.rollout},
                           {"--checkpoint", args.checkpoint},
                           {"checkpoint recipe", recipe_path(args.checkpoint)}});
  const std::vector<int> queries = parse_queries(args.query);
  const Rollout rollout = read_rollout(args.rollout);
  if (!rollout.checkpoint_path.empty() && !same_file(rollout.checkpoint_path, args.checkpoint)) {
    log_warn("trace: ", args.rollout, " was rolled out with ", rollout.checkpoint_path, ", not ",
             args.checkpoint, "; tracing ", args.checkpoint, " on its predictions");
  }
  ModelTrace trace = capture_rollout_trace(args.checkpoint, rollout, args.frame, queries);
  trace.rollout_path = args.rollout;
  write_trace(trace, args.out);
  std::printf(
      "wrote %s: the pass that predicted frame %d of %s from its own frames %d..%d, "
      "%zu levels, %zu filter records\n",
      args.out.c_str(), trace.frame + 1, args.rollout.c_str(), trace.frame - 2, trace.frame,
      trace.levels.size(), trace.queries.size());
}

void run_trace(const TraceArgs& args) {
  require_int_in_range("--frame", args.frame, 2, kMaxFrameOption);
  if (args.voxel_given) require_in_range("--voxel", args.voxel, 0, kMaxVoxelOption, true);
  if (args.scene.empty() == args.rollout.empty()) {
    throw ValueError("--scene", "give a scene (--scene) or a rollout (--rollout), not both");
  }
  if (!args.rollout.empty()) {
    run_rollout_trace(args);
    return;
  }
  require_readable_file(args.checkpoint);
  require_readable_file(args.scene);
  require_output_directory("--out", args.out);
  require_distinct_output("--out", args.out,
                          {{"--scene", args.scene},
                           {"--checkpoint", args.checkpoint},
                           {"checkpoint recipe", recipe_path(args.checkpoint)}});
  const std::vector<int> queries = parse_queries(args.query);
  const CheckpointInfo info = read_checkpoint_info(args.checkpoint);
  const Scene scene = read_scene(args.scene);
  SamplingOptions sampling = checkpoint_sampling(args.checkpoint, info.config);
  if (args.voxel > 0) sampling.voxel = args.voxel;
  const ModelPoints points = build_model_points(scene, sampling);
  ModelTrace trace = capture_trace(args.checkpoint, scene, points, args.frame, queries);
  trace.scene_path = args.scene;
  write_trace(trace, args.out);
  std::printf("wrote %s: frame %d, %zu levels (", args.out.c_str(), trace.frame,
              trace.levels.size());
  for (size_t l = 0; l < trace.levels.size(); ++l) {
    std::printf("%s%lld", l ? ", " : "", static_cast<long long>(trace.levels[l].points.rows()));
  }
  std::printf(" points), %zu feature records, %zu filter records\n", trace.features.size(),
              trace.queries.size());
}

}  // namespace

void add_trace_command(CLI::App& app) {
  auto args = std::make_shared<TraceArgs>();
  CLI::App* cmd = app.add_subcommand(
      "trace",
      "Record one forward pass of a checkpoint at one frame: every U-Net level's points, object\n"
      "ids and voxel, every neighbour list (same/relational/down/up), mesh interaction points,\n"
      "per-point feature norms after each block and the learned filter weights h(p_k - p_0) at\n"
      "the --query points. Written as HDF5 for the viewer and renderer (layout: README).\n"
      "With --rollout instead of --scene, the pass recorded is the one that predicted frame\n"
      "t+1 of that rollout from its own predicted frames t-2..t (not the ground truth): the\n"
      "neighbourhoods and filter weights the model really used there.");
  cmd->add_option("--checkpoint", args->checkpoint, "Checkpoint written by `dynscope train`")
      ->required();
  cmd->add_option("--scene", args->scene, "Scene file (HDF5): trace its ground-truth frames");
  cmd->add_option("--rollout", args->rollout,
                  "Rollout file (`dynscope rollout`): trace its own predicted frames");
  cmd->add_option("--frame", args->frame, "Frame t the model reads (>= 2)")->capture_default_str();
  cmd->add_option("--out", args->out, "Trace file to write (HDF5)")->required();
  cmd->add_option("--query", args->query, "Comma-separated level-0 point indices, e.g. 0,17,42");
  cmd->add_option("--voxel", args->voxel, "Point sampling voxel (default: the checkpoint's)")
      ->each([args](const std::string&) { args->voxel_given = true; });
  cmd->callback([args] { run_trace(*args); });
}

}  // namespace dynscope::app
