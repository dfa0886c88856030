// `dynscope generate`: simulate seeded ground-truth scenes with Bullet into HDF5 files + manifest.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>
#include <string>

#include "app/cli_util.h"
#include "app/commands.h"
#include "engine/sim/dataset.h"
#include "engine/sim/scenario.h"
#include "engine/sim/shapes.h"

namespace dynscope::app {
namespace {

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

void run_generate(const DatasetOptions& options) {
  const DatasetSummary summary = generate_with_progress(options);
  std::printf("wrote %lld %s scenes to %s (manifest %s)\n", static_cast<long long>(options.count),
              options.scenario.c_str(), options.out_dir.c_str(), summary.manifest_path.c_str());
  if (scenario_has_contact_label(options.scenario)) {
    std::printf(
        "target touched the zone in %lld of %lld scenes (%.0f%%)\n",
        static_cast<long long>(summary.positives), static_cast<long long>(options.count),
        100.0 * static_cast<double>(summary.positives) / static_cast<double>(options.count));
  }
  if (options.hide_outcome_frames > 0 || options.balance) {
    int64_t draws = 0;
    for (const DatasetEntry& e : summary.entries) draws += e.draws;
    std::printf("%lld trials drawn for %lld scenes\n", static_cast<long long>(draws),
                static_cast<long long>(options.count));
  }
}

}  // namespace

void add_generate_command(CLI::App& app) {
  auto args = std::make_shared<DatasetOptions>();
  CLI::App* cmd = app.add_subcommand(
      "generate",
      "Simulate ground-truth scenes with Bullet: one HDF5 scene file per trial plus a manifest.\n"
      "The same arguments always give the same files, whatever --jobs is.");
  cmd->footer(scenario_list());
  cmd->add_option("--scenario", args->scenario, "Scenario name (listed below)")->required();
  cmd->add_option("--count", args->count, "Number of scenes to generate (>= 1)")->required();
  cmd->add_option("--seed", args->seed, "Base seed; scene i is seeded with derive_seed(seed, i)")
      ->check(unsigned_integer())
      ->capture_default_str();
  cmd->add_option("--out", args->out_dir,
                  "Output directory (created if missing; files are replaced)")
      ->required();
  cmd->add_option("--jobs", args->jobs, "Worker threads (>= 1); does not change the results")
      ->capture_default_str();
  cmd->add_option("--frame-rate", args->frame_rate_hz,
                  "Stored frames per second (Hz), instead of the scenario's own: the same\n"
                  "simulation stored more or less densely (a whole number of the 240 Hz physics\n"
                  "steps per frame; e.g. 60 or 15 for the Physion-like scenes, stored at 30); over\n"
                  "the same time, or on to the next whole frame where the rate's interval does not\n"
                  "divide the scenario's physics steps");
  cmd->add_option("--hide-outcome", args->hide_outcome_frames,
                  "Physion-like scenarios: draw a trial again while its target touches the zone\n"
                  "in its first N frames, so that a model observing N frames cannot read the\n"
                  "outcome off them (e.g. 14 for the paper's 0.45 s window at 30 fps); the\n"
                  "manifest records each scene's draws and seed")
      ->capture_default_str();
  cmd->add_flag("--balance", args->balance,
                "Physion-like scenarios: draw a trial again until scene i's outcome is\n"
                "(i + i / 10) % 2, so that every 20 scenes (and each split) are half positive");
  cmd->add_option_function<std::string>(
         "--mesh-density",
         [args](const std::string& name) {
           args->mesh_density = parse_mesh_density(name, "--mesh-density");
         },
         "Tessellation of the stored meshes of primitive shapes (the simulation is the same):\n"
         "dense (default) spreads vertices over every face; sparse keeps the fewest that hold\n"
         "the shape (a box's 8 corners, a cylinder's two rims), so that flat faces have no\n"
         "vertices inside, for the model's mesh input with face reasoning")
      ->check(CLI::IsMember({"dense", "sparse"}))
      ->default_str("dense");
  cmd->add_option("--meshes", args->meshes_dir,
                  "Directory of mesh files (OBJ, PLY, STL, glTF, ...) drawn as objects by movi-c");
  cmd->callback([args] { run_generate(*args); });
}

}  // namespace dynscope::app
