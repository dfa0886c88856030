// `dynscope eval`: point error and contact accuracy of a checkpoint over a dataset split.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <exception>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "app/cli_util.h"
#include "app/commands.h"
#include "app/distributed_cli.h"
#include "engine/core/error.h"
#include "engine/core/progress.h"
#include "engine/io/temp_file.h"
#include "engine/model/torch_runtime.h"
#include "engine/rollout/evaluation.h"
#include "engine/rollout/model_predictor.h"
#include "engine/sim/scenario.h"
#include "engine/train/process_group.h"
#include "engine/train/train_options.h"

namespace dynscope::app {
namespace {

struct EvalArgs {
  std::string checkpoint;
  std::vector<std::string> data;
  std::string split = "test";
  std::string json;
  int observed = 3;
  int max_scenes = 0;
  double threshold = 0.0;
  double threshold_fraction = kContactThresholdFraction;
  std::vector<std::string> scenario_threshold_fraction;  // SCENARIO=FRACTION
  double voxel = 0.0;
  bool voxel_given = false;
  bool threshold_given = false;
  bool no_baseline = false;
  int threads = 0;
  DistributedArgs dist;
};

// One rank of a data-parallel evaluation: scenes i with i mod W = rank; rank 0 gathers every
// rank's results and summarises them in split order (the same numbers as one process).
void run_eval_rank(const EvalArgs& args, const DistributedOptions& dist, const DatasetSplit& split,
                   const LoadedModel& model, const EvalOptions& options) {
  ProcessGroup group(dist);
  const int world = group.world_size();
  if (group.rank() == 0) {
    std::printf("distributed: %s backend, world size %d: %zu scenes shared out\n",
                group.backend().c_str(), world, split.items.size());
    std::fflush(stdout);
  }
  nlohmann::json mine = {{"voxel", 0.0}, {"threshold", 0.0}, {"scenes", nlohmann::json::array()}};
  std::unique_ptr<Progress> progress;
  const int64_t share =
      (static_cast<int64_t>(split.items.size()) - group.rank() + world - 1) / world;
  if (group.rank() == 0) progress = std::make_unique<Progress>("eval " + args.split, share);
  for (size_t i = static_cast<size_t>(group.rank()); i < split.items.size();
       i += static_cast<size_t>(world)) {
    double voxel = 0.0, threshold = 0.0;
    const SceneEvaluation e =
        evaluate_scene(split.items[i], model.predict, options, &voxel, &threshold);
    mine["voxel"] = voxel;
    mine["threshold"] = threshold;
    mine["scenes"].push_back({{"index", i}, {"result", scene_evaluation_to_json(e)}});
    if (progress) progress->advance();
  }
  if (progress) progress->finish();
  const std::vector<std::string> all = group.gather_bytes("evaluations", mine.dump());
  if (group.rank() != 0) return;
  std::vector<SceneEvaluation> scenes(split.items.size());
  std::vector<bool> have(split.items.size(), false);
  double voxel = 0.0, threshold = 0.0;
  for (const std::string& text : all) {
    const nlohmann::json j = nlohmann::json::parse(text);
    if (!j.at("scenes").empty()) {
      voxel = j.at("voxel").get<double>();
      threshold = j.at("threshold").get<double>();
    }
    for (const nlohmann::json& s : j.at("scenes")) {
      const size_t i = s.at("index").get<size_t>();
      scenes.at(i) = scene_evaluation_from_json(s.at("result").get<std::string>());
      have.at(i) = true;
    }
  }
  if (std::find(have.begin(), have.end(), false) != have.end()) {
    throw Error("data-parallel evaluation: a rank's scenes are missing from the gathered results");
  }
  const EvalSummary summary =
      summarize_evaluation(split, options, std::move(scenes), voxel, threshold);
  std::fputs(eval_table(summary).c_str(), stdout);
  if (!args.json.empty()) write_text_file_atomically(args.json, eval_to_json(summary));
}

// The --scenario-threshold-fraction values (SCENARIO=FRACTION) as a map; throws ValueError for a
// malformed value, an unknown scenario, a fraction out of range or a scenario named twice.
std::map<std::string, double> scenario_fractions(const std::vector<std::string>& values) {
  const char* option = "--scenario-threshold-fraction";
  std::map<std::string, double> out;
  for (const std::string& v : values) {
    const size_t eq = v.find('=');
    const std::string name = v.substr(0, eq);
    double fraction = 0.0;
    size_t used = 0;
    try {
      if (eq != std::string::npos) fraction = std::stod(v.substr(eq + 1), &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (eq == std::string::npos || name.empty() || used == 0 || used != v.size() - eq - 1) {
      throw ValueError(option, "expected SCENARIO=FRACTION (e.g. drop=1), got '" + v + "'");
    }
    if (!is_scenario(name)) scenario_summary(name);  // throws, listing the scenarios
    require_in_range(option, fraction, 0, 1e6, true);
    if (!out.emplace(name, fraction).second) throw ValueError(option, name + " is named twice");
  }
  return out;
}

void run_eval(const EvalArgs& args) {
  require_int_in_range("--observed", args.observed, 3, kMaxFrameOption);
  if (args.voxel_given) require_in_range("--voxel", args.voxel, 0, kMaxVoxelOption, true);
  if (args.threshold_given)
    require_in_range("--threshold", args.threshold, 0, kMaxVoxelOption, true);
  require_in_range("--threshold-fraction", args.threshold_fraction, 0, 1e6, true);
  const std::map<std::string, double> fractions =
      scenario_fractions(args.scenario_threshold_fraction);
  require_int_in_range("--threads", args.threads, 0, max_threads_option(), "(0: default)");
  require_readable_file(args.checkpoint);
  if (args.max_scenes != 0) require_int_in_range("--max-scenes", args.max_scenes, 1, 1 << 30);
  const DatasetSplit split = read_dataset_splits(args.data, args.split, args.max_scenes);
  if (split.items.empty())
    throw ValueError("split", split.dir + " has no " + args.split + " scenes");
  std::vector<NamedPath> inputs = {{"--checkpoint", args.checkpoint},
                                   {"checkpoint recipe", recipe_path(args.checkpoint)}};
  for (const std::string& dir : args.data)
    inputs.push_back({"dataset manifest", dir + "/manifest.json"});
  for (const DatasetItem& item : split.items) inputs.push_back({"dataset scene", item.path});
  require_output_directory("--json", args.json);
  require_distinct_output("--json", args.json, inputs);
  // Started as a rank (launcher, torchrun or srun), or the launcher of ranks, or one process.
  const std::optional<DistributedOptions> dist = DistributedOptions::from_environment();
  if (!dist && args.dist.nproc * args.dist.nnodes > 1) {
    launch_command_ranks(args.dist, args.dist.nproc, args.dist.cmd->count("--threads") > 0,
                         args.threads);
    return;
  }
  set_torch_threads(args.threads);
  const LoadedModel model = load_model(args.checkpoint);
  EvalOptions options;
  options.observed_frames = args.observed;
  options.sampling = checkpoint_sampling(args.checkpoint, model.config);
  if (args.voxel > 0) options.sampling.voxel = args.voxel;
  options.contact_threshold = args.threshold;
  options.threshold_fraction = args.threshold_fraction;
  options.scenario_threshold_fraction = fractions;
  options.baseline = !args.no_baseline;
  if (dist) {
    run_eval_rank(args, *dist, split, model, options);
    return;
  }
  Progress progress("eval " + args.split, static_cast<int64_t>(split.items.size()));
  const EvalSummary summary = evaluate_split(split, model.predict, options, &progress);
  progress.finish();
  std::fputs(eval_table(summary).c_str(), stdout);
  if (!args.json.empty()) write_text_file_atomically(args.json, eval_to_json(summary));
}

}  // namespace

void add_eval_command(CLI::App& app) {
  auto args = std::make_shared<EvalArgs>();
  CLI::App* cmd = app.add_subcommand(
      "eval",
      "Evaluate a checkpoint on a dataset split: Kubric-style mean point distance at the end of\n"
      "the rollout (and per frame), Physion-style contact accuracy (contact predicted when the\n"
      "minimum target-zone point distance falls below the threshold in any frame, observed\n"
      "frames included), next to a physics-free constant-velocity-plus-gravity baseline\n"
      "(Kabsch-rigidified, floor clamp at z = 0) and the threshold rule applied to ground truth.\n"
      "--nproc N shares the scenes out over N ranks (c10d, like `train --nproc`); rank 0\n"
      "gathers one result, identical to a single process's.");
  cmd->add_option("--checkpoint", args->checkpoint, "Checkpoint written by `dynscope train`")
      ->required();
  cmd->add_option("--data", args->data,
                  "Dataset directory (with manifest.json); several (e.g. the seven Physion-like\n"
                  "scenarios) are evaluated as one set, with contact accuracy per scenario and\n"
                  "their mean")
      ->required();
  cmd->add_option("--split", args->split,
                  "train, val, test, or all (every scene: a held-out dataset generated apart)")
      ->capture_default_str();
  cmd->add_option("--max-scenes", args->max_scenes,
                  "Evaluate at most N scenes of the split (of each --data directory), evenly\n"
                  "spaced over it (0: all), e.g. a sample of the training split beside the\n"
                  "validation split's numbers");
  cmd->add_option("--json", args->json, "Also write every number as JSON to this file");
  cmd->add_option("--observed", args->observed, "Ground-truth frames before prediction (>= 3)")
      ->capture_default_str();
  cmd->add_option("--threshold", args->threshold,
                  "Contact distance in scene units (default: --threshold-fraction x voxel)")
      ->each([args](const std::string&) { args->threshold_given = true; });
  cmd->add_option("--threshold-fraction", args->threshold_fraction,
                  "Contact threshold as a fraction of the sampling voxel")
      ->capture_default_str();
  cmd->add_option("--scenario-threshold-fraction", args->scenario_threshold_fraction,
                  "SCENARIO=FRACTION: that scenario's contact threshold as a fraction of the\n"
                  "voxel, in place of --threshold and --threshold-fraction (repeatable). The\n"
                  "Physion protocol of the paper: --observed 14 --threshold-fraction 1.5\n"
                  "--scenario-threshold-fraction drop=1 --scenario-threshold-fraction contain=1");
  cmd->add_option("--voxel", args->voxel, "Point sampling voxel (default: the checkpoint's)")
      ->each([args](const std::string&) { args->voxel_given = true; });
  cmd->add_flag("--no-baseline", args->no_baseline, "Skip the constant-velocity baseline");
  cmd->add_option("--threads", args->threads, "LibTorch threads (0: default)")
      ->capture_default_str();
  add_distributed_options(cmd, args->dist, "evaluation (scenes shared out, one result)");
  cmd->callback([args] { run_eval(*args); });
}

}  // namespace dynscope::app
