// `dynscope generate`: simulate seeded ground-truth scenes with Bullet into HDF5 files + manifest.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>
#include <string>

#include "app/commands.h"
#include "engine/core/progress.h"
#include "engine/sim/dataset.h"
#include "engine/sim/scenario.h"

namespace dynscope::app {
namespace {

struct GenerateArgs {
  std::string scenario;
  int64_t count = 0;
  uint64_t seed = 0;
  std::string out;
  int jobs = 1;
  std::string meshes;
};

std::string scenario_list() {
  std::string text = "Scenarios:\n";
  for (const std::string& name : scenario_names()) {
    char line[160];
    std::snprintf(line, sizeof line, "  %-9s %s\n", name.c_str(), scenario_summary(name).c_str());
    text += line;
  }
  text +=
      "\nOutput: DIR/<scenario>_NNNN.h5 (one HDF5 scene per trial) and DIR/manifest.json "
      "(scenario,\n"
      "parameters, base seed, per-file seed and outcome, 80/10/10 train/val/test split by index).\n"
      "Scene parameters of every scenario: engine/sim/SCENARIOS.md.";
  return text;
}

void run_generate(const GenerateArgs& args) {
  DatasetOptions options;
  options.scenario = args.scenario;
  options.count = args.count;
  options.seed = args.seed;
  options.out_dir = args.out;
  options.jobs = args.jobs;
  options.meshes_dir = args.meshes;
  // Every option is checked (and the output directory created) before the first scene.
  check_dataset_options(options);
  Progress progress("generate " + args.scenario, args.count);
  const DatasetSummary summary = generate_dataset(options, &progress);
  progress.finish();
  std::printf("wrote %lld %s scenes to %s (manifest %s)\n", static_cast<long long>(args.count),
              args.scenario.c_str(), args.out.c_str(), summary.manifest_path.c_str());
  if (scenario_has_contact_label(args.scenario)) {
    std::printf("target touched the zone in %lld of %lld scenes (%.0f%%)\n",
                static_cast<long long>(summary.positives), static_cast<long long>(args.count),
                100.0 * static_cast<double>(summary.positives) / static_cast<double>(args.count));
  }
}

}  // namespace

void add_generate_command(CLI::App& app) {
  auto args = std::make_shared<GenerateArgs>();
  CLI::App* cmd = app.add_subcommand(
      "generate",
      "Simulate ground-truth scenes with Bullet: one HDF5 scene file per trial plus a manifest.\n"
      "The same arguments always give the same files, whatever --jobs is.");
  cmd->footer(scenario_list());
  cmd->add_option("--scenario", args->scenario, "Scenario name (listed below)")->required();
  cmd->add_option("--count", args->count, "Number of scenes to generate (>= 1)")->required();
  cmd->add_option("--seed", args->seed, "Base seed; scene i is seeded with derive_seed(seed, i)")
      ->capture_default_str();
  cmd->add_option("--out", args->out, "Output directory (created if missing; files are replaced)")
      ->required();
  cmd->add_option("--jobs", args->jobs, "Worker threads (>= 1); does not change the results")
      ->capture_default_str();
  cmd->add_option("--meshes", args->meshes,
                  "Directory of mesh files (OBJ, PLY, STL, glTF, ...) drawn as objects by movi-c");
  cmd->callback([args] { run_generate(*args); });
}

}  // namespace dynscope::app
