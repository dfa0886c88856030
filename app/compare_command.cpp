// `dynscope compare`: several runs' evaluations over seeds, side by side, with paired per-scene
// differences (the numbers a claim like "PointConv U-Net < GNN U-Net" rests on).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "app/cli_util.h"
#include "app/commands.h"
#include "engine/core/error.h"
#include "engine/io/temp_file.h"
#include "engine/rollout/eval_comparison.h"

namespace dynscope::app {
namespace {

struct CompareArgs {
  std::vector<std::string> runs;
  std::string json;
};

// "LABEL=A.json,B.json" (or a bare "A.json", labelled by its file name) to a run's evaluations.
RunEvaluations read_run(const std::string& spec) {
  RunEvaluations run;
  const size_t eq = spec.find('=');
  std::string files = spec;
  if (eq != std::string::npos) {
    run.label = spec.substr(0, eq);
    files = spec.substr(eq + 1);
    if (run.label.empty()) throw ValueError(spec, "the label before '=' is empty");
  }
  size_t start = 0;
  while (start <= files.size()) {
    const size_t comma = std::min(files.find(',', start), files.size());
    const std::string path = files.substr(start, comma - start);
    if (path.empty()) throw ValueError(spec, "an empty file name in the list");
    require_readable_file(path);
    run.paths.push_back(path);
    run.seeds.push_back(read_eval_json(path));
    start = comma + 1;
  }
  if (run.label.empty()) run.label = std::filesystem::path(run.paths.front()).stem().string();
  return run;
}

void run_compare(const CompareArgs& args) {
  require_output_directory("--json", args.json);
  std::vector<RunEvaluations> runs;
  for (const std::string& spec : args.runs) runs.push_back(read_run(spec));
  std::vector<NamedPath> inputs;
  for (const RunEvaluations& run : runs) {
    for (const std::string& path : run.paths)
      inputs.push_back({"evaluation of " + run.label, path});
  }
  require_distinct_output("--json", args.json, inputs);
  const EvalComparison c = compare_evaluations(runs);
  std::fputs(comparison_table(c).c_str(), stdout);
  if (!args.json.empty()) write_text_file_atomically(args.json, comparison_to_json(c));
}

}  // namespace

void add_compare_command(CLI::App& app) {
  auto args = std::make_shared<CompareArgs>();
  CLI::App* cmd = app.add_subcommand(
      "compare",
      "Compare runs from their evaluations (`dynscope eval --json` files of one split): each "
      "run's end error and contact accuracy as mean ± sd over its seeds, beside the "
      "constant-velocity floor and the contact ceiling, and every pair of runs scene by scene "
      "(each scene's end error averaged over the run's seeds, the difference A - B with its "
      "standard error over scenes, how many scenes A wins, and whether the seed intervals "
      "overlap). Every file must cover the same scenes.");
  cmd->add_option("runs", args->runs,
                  "Runs as LABEL=SEED1.json,SEED2.json,... (or one file, labelled by its name), in "
                  "the order of the claim")
      ->required();
  cmd->add_option("--json", args->json, "Also write every number as JSON to this file");
  cmd->callback([args] { run_compare(*args); });
}

}  // namespace dynscope::app
