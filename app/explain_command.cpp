// `dynscope explain`: which neighbourhoods made a rollout go wrong, from the model's own state.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <fstream>
#include <memory>
#include <optional>
#include <string>

#include "app/cli_util.h"
#include "app/commands.h"
#include "app/explain_run.h"
#include "engine/core/error.h"
#include "engine/core/log.h"
#include "engine/io/rollout_file.h"
#include "engine/io/scene_file.h"
#include "engine/io/temp_file.h"

namespace dynscope::app {

ExplainRun explain_checkpoint_rollout(const ExplainRequest& request) {
  require_readable_file(request.checkpoint);
  require_readable_file(request.rollout_path);
  ExplainRun run;
  run.rollout = read_rollout(request.rollout_path);
  const Rollout& r = run.rollout;
  if (!r.checkpoint_path.empty() && !same_file(r.checkpoint_path, request.checkpoint)) {
    log_warn("explain: ", request.rollout_path, " was rolled out with ", r.checkpoint_path,
             ", not ", request.checkpoint, "; explaining ", request.checkpoint,
             " on its predictions");
  }
  const std::string scene_path = find_rollout_scene(r, request.rollout_path);
  std::optional<Scene> scene;
  if (!scene_path.empty()) {
    try {
      scene = read_scene(scene_path);
    } catch (const Error& e) {
      log_warn("explain: objects are named by id: ", e.what());
    }
  }
  run.names = object_names(r, scene ? &*scene : nullptr);
  if (!request.object.empty() && request.point >= 0) {
    throw ValueError("--object", "give --object or --point, not both");
  }
  const int32_t object =
      request.object.empty() ? -1 : parse_object(request.object, r, run.names, "--object");
  if (request.point >= r.num_points()) {
    throw ValueError("--point", std::to_string(request.point) + " outside [0, " +
                                    std::to_string(r.num_points()) + ") (the rollout's points)");
  }
  const RolloutExplainer explainer(request.checkpoint);
  DivergenceOptions options;
  options.threshold = request.threshold;
  run.divergence = find_divergence(r, explainer.config(), options);
  const PassRange passes = rollout_passes(r);
  if (request.frame >= 0 && (request.frame < passes.first || request.frame > passes.last)) {
    throw ValueError("--frame", std::to_string(request.frame) + " outside [" +
                                    std::to_string(passes.first) + ", " +
                                    std::to_string(passes.last) +
                                    "]: pass t reads predicted frames t-2..t and produces t+1");
  }
  const ExplainSelection selection = resolve_selection(r, run.divergence, request.frame, object,
                                                       request.point, request.target, "--frame");
  run.explanation = explainer.explain(r, selection);
  return run;
}

namespace {

struct ExplainArgs {
  ExplainRequest request;
  std::string target = "error";
  std::string json;
  int top = 8;
};

void print_run(const ExplainRun& run, const ExplainArgs& args) {
  const Rollout& r = run.rollout;
  const Divergence& d = run.divergence;
  const Explanation& e = run.explanation;
  std::printf("rollout %s: %s, %d frames (%d observed), %lld points\n",
              args.request.rollout_path.c_str(), r.scenario.c_str(), r.num_frames(),
              r.observed_frames, static_cast<long long>(r.num_points()));
  if (d.found()) {
    std::printf("divergence: pass %d -> frame %d, %s's error grows %.4g per frame to %.4g\n",
                d.frame, d.frame + 1, run.names(d.object).c_str(), d.growth, d.error);
  } else {
    std::printf("divergence: none (no object's error grows above the threshold)\n");
  }
  std::printf("  threshold %.4g: %s\n", d.threshold, d.threshold_rule.c_str());
  if (d.found()) {
    std::string pairs;
    for (const ContactPair& c : d.contacts) {
      pairs += (pairs.empty() ? "" : ", ") + run.names(c.a) + " - " + run.names(c.b) + " (" +
               std::to_string(c.edges) + " edges)";
    }
    std::printf("  in contact there (the model's relational lists): %s\n",
                pairs.empty() ? "none" : pairs.c_str());
  }
  std::printf(
      "explaining %s at pass %d (predicting frame %d): error %.4g, growth %+.4g per frame\n",
      explained_subject(e, run.names).c_str(), e.frame, e.frame + 1, e.error, e.error_growth);
  std::printf("  attributed: %s of the raw prediction (before rigid projection) = %.4g\n",
              explain_target_name(e.target), e.value);
  if (e.contributors.empty()) {
    std::printf("  no neighbour edge reaches it: only its own points' features matter\n");
    return;
  }
  std::printf(
      "  sum of |dE/dg| over all %s edges: %.3g (%.2g %% of E): to first order no set of\n"
      "  neighbour messages moves E by more\n",
      "neighbour", e.edge_total, e.value > 0 ? 100.0 * e.edge_total / e.value : 0.0);
  std::printf(
      "  share of |gradient x input| over the edges of each neighbour list, by level and\n"
      "  source object (effect > 0: those neighbours pushed the %s up)\n",
      explain_target_name(e.target));
  for (const std::string& line : contributor_lines(e, run.names, static_cast<size_t>(args.top))) {
    std::printf("  %s\n", line.c_str());
  }
}

void run_explain(ExplainArgs& args) {
  require_int_in_range("--top", args.top, 0, 1000000, "(0: all)");
  args.request.target = parse_explain_target(args.target);
  if (!args.json.empty()) {
    require_output_directory("--json", args.json);
    require_distinct_output(
        "--json", args.json,
        {{"--rollout", args.request.rollout_path}, {"--checkpoint", args.request.checkpoint}});
  }
  const ExplainRun run = explain_checkpoint_rollout(args.request);
  print_run(run, args);
  if (!args.json.empty()) {
    TempFile out(args.json);
    {
      std::ofstream f(out.path());
      f << explanation_to_json(run.explanation, run.names, &run.divergence);
      if (!f) throw IoError(args.json, "cannot write");
    }
    out.commit();
    std::printf("wrote %s\n", args.json.c_str());
  }
}

}  // namespace

void add_explain_command(CLI::App& app) {
  auto args = std::make_shared<ExplainArgs>();
  CLI::App* cmd = app.add_subcommand(
      "explain",
      "Explain a rollout from the model's own state: find where it diverges (the first pass\n"
      "whose per-object error growth exceeds a threshold, by default half the largest growth\n"
      "in the rollout) and which neighbourhoods made the chosen object or point go wrong there.\n"
      "The pass at --frame t reads the rollout's own predicted frames t-2..t; every edge of\n"
      "every neighbour list (object kNN 'same', 'relational' within r, 'down'/'up' between\n"
      "levels, mesh 'face_vertices'/'senders'/'vertex_points') gets a gate g = 1 on its message,\n"
      "and the gradient x input dE/dg of the chosen points' error E (or predicted acceleration)\n"
      "is summed per list, level and source object into shares that sum to 1.");
  cmd->add_option("--checkpoint", args->request.checkpoint,
                  "Checkpoint written by `dynscope train`")
      ->required();
  cmd->add_option("--rollout", args->request.rollout_path, "Rollout file (`dynscope rollout`)")
      ->required();
  cmd->add_option("--frame", args->request.frame,
                  "Pass t to explain (it predicted frame t+1; default: the divergence)")
      ->check(unsigned_integer());
  cmd->add_option("--object", args->request.object,
                  "Object (name or id) whose points' mean to explain (default: the diverging one)");
  cmd->add_option("--point", args->request.point, "One rollout point to explain instead")
      ->check(unsigned_integer());
  cmd->add_option("--target", args->target,
                  "What to attribute: error (|prediction - truth| at t+1) or acceleration")
      ->capture_default_str();
  cmd->add_option("--threshold", args->request.threshold,
                  "Divergence threshold in error growth per frame (default: derived)")
      ->check(finite_number(0, 1e12, false));
  cmd->add_option("--top", args->top, "Contributors to print (0: all)")->capture_default_str();
  cmd->add_option("--json", args->json, "Also write the explanation as JSON");
  cmd->callback([args] { run_explain(*args); });
}

}  // namespace dynscope::app
