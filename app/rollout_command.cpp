// `dynscope rollout`: autoregressive prediction of one scene with a checkpoint, written to HDF5.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>
#include <string>

#include "app/cli_util.h"
#include "app/commands.h"
#include "engine/core/progress.h"
#include "engine/io/rollout_file.h"
#include "engine/io/scene_file.h"
#include "engine/model/torch_runtime.h"
#include "engine/rollout/evaluation.h"
#include "engine/rollout/metrics.h"
#include "engine/rollout/model_predictor.h"
#include "engine/train/train_options.h"

namespace dynscope::app {
namespace {

struct RolloutArgs {
  std::string checkpoint;
  std::string scene;
  std::string out;
  int observed = 3;
  int frames = 0;
  double voxel = 0.0;
  bool voxel_given = false;
  int threads = 0;
};

void run_rollout_command(const RolloutArgs& args) {
  require_int_in_range("--observed", args.observed, 3, kMaxFrameOption);
  require_int_in_range("--frames", args.frames, 0, kMaxFrameOption, "(0: all frames)");
  if (args.voxel_given) require_in_range("--voxel", args.voxel, 0, kMaxVoxelOption, true);
  require_int_in_range("--threads", args.threads, 0, max_threads_option(), "(0: default)");
  require_readable_file(args.checkpoint);  // before the progress bar starts
  require_readable_file(args.scene);
  require_output_directory("--out", args.out);
  require_distinct_output("--out", args.out,
                          {{"--scene", args.scene},
                           {"--checkpoint", args.checkpoint},
                           {"checkpoint recipe", recipe_path(args.checkpoint)}});
  set_torch_threads(args.threads);
  const Scene scene = read_scene(args.scene);
  RolloutOptions options;
  options.observed_frames = args.observed;
  options.frames = args.frames;
  const int frames = args.frames > 0 ? args.frames : scene.num_frames();
  Progress progress("rollout", std::max(0, frames - args.observed));
  ModelPoints points;
  const Rollout r = rollout_checkpoint(args.checkpoint, scene, args.scene, options, args.voxel,
                                       &progress, &points);
  progress.finish();
  // Everything that can fail runs before the file is written: a failed command leaves --out as
  // it was.
  const Rollout baseline = run_baseline_rollout(scene, points, options);
  write_rollout(r, args.out);
  std::printf("wrote %s: %d frames (%d observed), %lld points\n", args.out.c_str(), r.num_frames(),
              r.observed_frames, static_cast<long long>(r.num_points()));
  std::printf(
      "end point error %.4f (mean distance to truth at frame %d, scene units); "
      "constant-velocity-plus-gravity baseline %.4f\n",
      r.point_error.back(), r.num_frames() - 1, baseline.point_error.back());
  if (r.has_contact()) {
    const double threshold = kContactThresholdFraction * r.sampling_voxel;
    std::printf(
        "target-zone contact (threshold %.4g = %.2f x voxel %.4g): truth %s, predicted %s, "
        "baseline %s\n",
        threshold, kContactThresholdFraction, r.sampling_voxel,
        contact_predicted(r.contact_distance_truth, threshold) ? "yes" : "no",
        contact_predicted(r.contact_distance_predicted, threshold) ? "yes" : "no",
        contact_predicted(baseline.contact_distance_predicted, threshold) ? "yes" : "no");
  }
}

}  // namespace

void add_rollout_command(CLI::App& app) {
  auto args = std::make_shared<RolloutArgs>();
  CLI::App* cmd = app.add_subcommand(
      "rollout",
      "Roll a trained model out on one scene: the first --observed frames come from ground truth,\n"
      "every later frame is predicted from the previous three, and each rigid object is projected\n"
      "to one rigid transform per step (Kabsch from its rest points). Writes predicted and true\n"
      "points, fitted poses and per-frame metrics to an HDF5 rollout file (layout: README).");
  cmd->add_option("--checkpoint", args->checkpoint, "Checkpoint written by `dynscope train`")
      ->required();
  cmd->add_option("--scene", args->scene, "Scene file (HDF5)")->required();
  cmd->add_option("--out", args->out, "Rollout file to write (HDF5)")->required();
  cmd->add_option("--observed", args->observed,
                  "Ground-truth frames before prediction starts (>= 3: the model reads p(t), "
                  "p(t-1), p(t-2))")
      ->capture_default_str();
  cmd->add_option("--frames", args->frames, "Frames to roll out (0: all frames of the scene)")
      ->capture_default_str();
  cmd->add_option("--voxel", args->voxel,
                  "Point sampling voxel (default: the checkpoint's recipe, else 0.2 for movi-*, "
                  "0.05 otherwise)")
      ->each([args](const std::string&) { args->voxel_given = true; });
  cmd->add_option("--threads", args->threads, "LibTorch threads (0: default)")
      ->capture_default_str();
  cmd->callback([args] { run_rollout_command(*args); });
}

}  // namespace dynscope::app
