// Dataset evaluation over model and baseline rollouts.
#include "engine/rollout/evaluation.h"

#include <algorithm>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "engine/core/error.h"
#include "engine/io/scene_file.h"
#include "engine/io/temp_file.h"

namespace dynscope {

namespace {

constexpr const char* kContactLabel = "target_contacting_zone";

int scene_label(const Scene& scene, int fallback) {
  const auto it = scene.labels.find(kContactLabel);
  if (it == scene.labels.end()) return fallback;
  for (double v : it->second) {
    if (v > 0.5) return 1;
  }
  return 0;
}

double min_of(const std::vector<double>& v) {
  return v.empty() ? 0.0 : *std::min_element(v.begin(), v.end());
}

void add_curve(std::vector<double>& sum, const std::vector<double>& curve, int count) {
  if (count == 0) {
    sum = curve;
    return;
  }
  sum.resize(std::min(sum.size(), curve.size()));
  for (size_t i = 0; i < sum.size(); ++i) sum[i] += curve[i];
}

void finish(ScenarioSummary& s) {
  if (s.scenes > 0) {
    s.model_end_error /= s.scenes;
    s.baseline_end_error /= s.scenes;
    for (double& v : s.model_curve) v /= s.scenes;
    for (double& v : s.baseline_curve) v /= s.scenes;
  }
  if (s.labelled > 0) {
    s.model_accuracy /= s.labelled;
    s.baseline_accuracy /= s.labelled;
    s.truth_accuracy /= s.labelled;
  }
}

void accumulate(ScenarioSummary& s, const SceneEvaluation& e) {
  add_curve(s.model_curve, e.model_curve, s.scenes);
  add_curve(s.baseline_curve, e.baseline_curve, s.scenes);
  ++s.scenes;
  s.model_end_error += e.model_curve.back();
  s.baseline_end_error += e.baseline_curve.empty() ? 0.0 : e.baseline_curve.back();
  if (e.label >= 0 && e.has_contact) {
    ++s.labelled;
    s.model_accuracy += (e.model_contact == (e.label == 1)) ? 1 : 0;
    s.baseline_accuracy += (e.baseline_contact == (e.label == 1)) ? 1 : 0;
    s.truth_accuracy += (e.truth_contact == (e.label == 1)) ? 1 : 0;
  }
}

}  // namespace

const char* const kBaselineDescription =
    "constant velocity + gravity (p(t+1) = p(t) + v(t) - g dt^2 z), Kabsch-rigidified, "
    "floor clamp at z = 0";

Rollout run_baseline_rollout(const Scene& scene, const ModelPoints& points,
                             RolloutOptions options) {
  options.floor_clamp = true;
  return run_rollout(scene, points,
                     constant_velocity_predictor(default_gravity(scene.scenario), scene.dt_s),
                     options);
}

namespace {
// The contact threshold of scenes without one of their own.
double default_contact_threshold(const EvalOptions& options, double voxel) {
  return options.contact_threshold > 0 ? options.contact_threshold
                                       : options.threshold_fraction * voxel;
}
}  // namespace

double contact_threshold_for(const EvalOptions& options, const std::string& scenario,
                             double voxel) {
  const auto own = options.scenario_threshold_fraction.find(scenario);
  if (own != options.scenario_threshold_fraction.end()) return own->second * voxel;
  return default_contact_threshold(options, voxel);
}

SceneEvaluation evaluate_scene(const DatasetItem& item, const StepPredictor& model,
                               const EvalOptions& options, double* voxel, double* threshold) {
  try {
    const Scene scene = read_scene(item.path);
    const ModelPoints points = build_model_points(scene, options.sampling);
    const double contact = contact_threshold_for(options, scene.scenario, points.voxel);
    if (voxel) *voxel = points.voxel;
    if (threshold) *threshold = default_contact_threshold(options, points.voxel);
    RolloutOptions ro;
    ro.observed_frames = options.observed_frames;
    const Rollout m = run_rollout(scene, points, model, ro);
    SceneEvaluation e;
    e.file = item.file;
    e.scenario = scene.scenario;
    e.frames = m.num_frames();
    e.label = scene_label(scene, item.outcome);
    e.model_curve = m.point_error;
    e.has_contact = m.has_contact();
    if (e.has_contact) {
      e.truth_contact = contact_predicted(m.contact_distance_truth, contact);
      e.model_contact = contact_predicted(m.contact_distance_predicted, contact);
      e.truth_min_distance = min_of(m.contact_distance_truth);
      e.model_min_distance = min_of(m.contact_distance_predicted);
    }
    if (options.baseline) {
      const Rollout b = run_baseline_rollout(scene, points, ro);
      e.baseline_curve = b.point_error;
      if (e.has_contact) {
        e.baseline_contact = contact_predicted(b.contact_distance_predicted, contact);
        e.baseline_min_distance = min_of(b.contact_distance_predicted);
      }
    }
    return e;
  } catch (const IoError&) {
    throw;
  } catch (const Error& e) {
    throw Error(item.path + ": " + e.what());
  }
}

EvalSummary summarize_evaluation(const DatasetSplit& split, const EvalOptions& options,
                                 std::vector<SceneEvaluation> scenes, double voxel,
                                 double threshold) {
  EvalSummary out;
  out.dir = split.dir;
  out.split = split.split;
  out.observed_frames = options.observed_frames;
  out.voxel = voxel;
  out.threshold = threshold;
  for (SceneEvaluation& e : scenes) {
    if (options.scenario_threshold_fraction.count(e.scenario) > 0) {
      out.scenario_thresholds[e.scenario] = contact_threshold_for(options, e.scenario, voxel);
    }
    accumulate(out.scenarios[e.scenario], e);
    accumulate(out.scenarios["all"], e);
    out.scenes.push_back(std::move(e));
  }
  for (auto& [name, s] : out.scenarios) {
    finish(s);
    if (name == "all" || s.labelled == 0) continue;
    ++out.contact.scenarios;
    out.contact.model += s.model_accuracy;
    out.contact.baseline += s.baseline_accuracy;
    out.contact.truth += s.truth_accuracy;
  }
  if (out.contact.scenarios > 0) {
    out.contact.model /= out.contact.scenarios;
    out.contact.baseline /= out.contact.scenarios;
    out.contact.truth /= out.contact.scenarios;
  }
  return out;
}

EvalSummary evaluate_split(const DatasetSplit& split, const StepPredictor& model,
                           const EvalOptions& options, Progress* progress) {
  std::vector<SceneEvaluation> scenes;
  double voxel = 0.0, threshold = 0.0;
  for (const DatasetItem& item : split.items) {
    scenes.push_back(evaluate_scene(item, model, options, &voxel, &threshold));
    if (progress) progress->advance();
  }
  return summarize_evaluation(split, options, std::move(scenes), voxel, threshold);
}

std::string scene_evaluation_to_json(const SceneEvaluation& e) {
  const nlohmann::json j = {{"file", e.file},
                            {"scenario", e.scenario},
                            {"frames", e.frames},
                            {"label", e.label},
                            {"model_curve", e.model_curve},
                            {"baseline_curve", e.baseline_curve},
                            {"has_contact", e.has_contact},
                            {"truth_contact", e.truth_contact},
                            {"model_contact", e.model_contact},
                            {"baseline_contact", e.baseline_contact},
                            {"model_min_distance", e.model_min_distance},
                            {"baseline_min_distance", e.baseline_min_distance},
                            {"truth_min_distance", e.truth_min_distance}};
  return j.dump();
}

SceneEvaluation scene_evaluation_from_json(const std::string& text) {
  SceneEvaluation e;
  try {
    const nlohmann::json j = nlohmann::json::parse(text);
    e.file = j.at("file").get<std::string>();
    e.scenario = j.at("scenario").get<std::string>();
    e.frames = j.at("frames").get<int>();
    e.label = j.at("label").get<int>();
    e.model_curve = j.at("model_curve").get<std::vector<double>>();
    e.baseline_curve = j.at("baseline_curve").get<std::vector<double>>();
    e.has_contact = j.at("has_contact").get<bool>();
    e.truth_contact = j.at("truth_contact").get<bool>();
    e.model_contact = j.at("model_contact").get<bool>();
    e.baseline_contact = j.at("baseline_contact").get<bool>();
    e.model_min_distance = j.at("model_min_distance").get<double>();
    e.baseline_min_distance = j.at("baseline_min_distance").get<double>();
    e.truth_min_distance = j.at("truth_min_distance").get<double>();
  } catch (const nlohmann::json::exception& x) {
    throw FormatError("scene evaluation", "json", x.what());
  }
  return e;
}

std::string eval_to_json(const EvalSummary& s) {
  using nlohmann::json;
  json j;
  j["dir"] = s.dir;
  j["split"] = s.split;
  j["observed_frames"] = s.observed_frames;
  j["sampling_voxel"] = s.voxel;
  j["contact_threshold"] = s.threshold;
  if (!s.scenario_thresholds.empty()) j["scenario_contact_thresholds"] = s.scenario_thresholds;
  j["baseline"] = kBaselineDescription;
  if (s.contact.scenarios > 0) {
    j["contact_scenario_mean"] = {{"scenarios", s.contact.scenarios},
                                  {"contact_accuracy", s.contact.model},
                                  {"baseline_contact_accuracy", s.contact.baseline},
                                  {"truth_contact_accuracy", s.contact.truth}};
  }
  for (const auto& [name, a] : s.scenarios) {
    j["scenarios"][name] = {{"scenes", a.scenes},
                            {"end_error", a.model_end_error},
                            {"baseline_end_error", a.baseline_end_error},
                            {"error_curve", a.model_curve},
                            {"baseline_error_curve", a.baseline_curve},
                            {"labelled", a.labelled},
                            {"contact_accuracy", a.model_accuracy},
                            {"baseline_contact_accuracy", a.baseline_accuracy},
                            {"truth_contact_accuracy", a.truth_accuracy}};
  }
  for (const SceneEvaluation& e : s.scenes) {
    json se = {{"file", e.file},
               {"scenario", e.scenario},
               {"frames", e.frames},
               {"label", e.label},
               {"end_error", e.model_curve.back()},
               {"error_curve", e.model_curve},
               {"baseline_error_curve", e.baseline_curve}};
    if (e.has_contact) {
      se["truth_contact"] = e.truth_contact;
      se["contact"] = e.model_contact;
      se["baseline_contact"] = e.baseline_contact;
      se["truth_min_distance"] = e.truth_min_distance;
      se["min_distance"] = e.model_min_distance;
      se["baseline_min_distance"] = e.baseline_min_distance;
    }
    j["scenes"].push_back(se);
  }
  return j.dump(2) + "\n";
}

EvalSummary read_eval_json(const std::string& path) {
  const std::string text = read_text_file(path, "cannot open evaluation file");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    throw FormatError(path, "json",
                      "not a JSON file (parse error at byte " + std::to_string(e.byte) +
                          "); expected what `dynscope eval --json` writes");
  }
  const char* field = "split";
  try {
    DatasetSplit split;
    split.dir = j.at("dir").get<std::string>();
    split.split = j.at("split").get<std::string>();
    EvalOptions options;
    field = "observed_frames";
    options.observed_frames = j.at("observed_frames").get<int>();
    field = "sampling_voxel";
    const double voxel = j.at("sampling_voxel").get<double>();
    field = "contact_threshold";
    const double threshold = j.at("contact_threshold").get<double>();
    field = "scenes";
    std::vector<SceneEvaluation> scenes;
    for (const nlohmann::json& s : j.at("scenes")) {
      SceneEvaluation e;
      e.file = s.at("file").get<std::string>();
      e.scenario = s.at("scenario").get<std::string>();
      e.frames = s.at("frames").get<int>();
      e.label = s.at("label").get<int>();
      e.model_curve = s.at("error_curve").get<std::vector<double>>();
      e.baseline_curve = s.at("baseline_error_curve").get<std::vector<double>>();
      if (e.model_curve.empty()) throw FormatError(path, "scenes", e.file + " has no error curve");
      e.has_contact = s.contains("contact");
      if (e.has_contact) {
        e.model_contact = s.at("contact").get<bool>();
        e.truth_contact = s.at("truth_contact").get<bool>();
        e.baseline_contact = s.at("baseline_contact").get<bool>();
        e.model_min_distance = s.at("min_distance").get<double>();
        e.truth_min_distance = s.at("truth_min_distance").get<double>();
        e.baseline_min_distance = s.at("baseline_min_distance").get<double>();
      }
      scenes.push_back(std::move(e));
    }
    if (scenes.empty()) throw FormatError(path, "scenes", "the evaluation has no scene");
    EvalSummary summary = summarize_evaluation(split, options, std::move(scenes), voxel, threshold);
    field = "scenario_contact_thresholds";
    if (j.contains(field)) {
      summary.scenario_thresholds = j.at(field).get<std::map<std::string, double>>();
    }
    return summary;
  } catch (const nlohmann::json::exception& e) {
    throw FormatError(path, field, std::string("missing or malformed (") + e.what() + ")");
  }
}

std::string eval_table(const EvalSummary& s) {
  std::string out;
  char line[256];
  std::snprintf(line, sizeof line,
                "split %s, %d observed frames, sampling voxel %.4g, contact threshold %.4g",
                s.split.c_str(), s.observed_frames, s.voxel, s.threshold);
  out += line;
  std::string own;  // the scenarios with a threshold of their own
  for (const auto& [name, value] : s.scenario_thresholds) {
    std::snprintf(line, sizeof line, "%s%s %.4g", own.empty() ? "" : ", ", name.c_str(), value);
    own += line;
  }
  out += own.empty() ? "\n" : " (" + own + ")\n";
  std::snprintf(line, sizeof line, "%-10s %6s %12s %12s %8s %9s %9s %9s\n", "scenario", "scenes",
                "end error", "baseline", "labels", "contact", "baseline", "truth");
  out += line;
  auto percent = [](double v) {
    char text[32];
    std::snprintf(text, sizeof text, "%.1f%%", 100 * v);
    return std::string(text);
  };
  // Without the baseline (--no-baseline) its columns are "-", not zeros.
  const bool baseline = !s.scenarios.empty() && !s.scenarios.begin()->second.baseline_curve.empty();
  for (const auto& [name, a] : s.scenarios) {
    char end[32] = "-";
    if (baseline) std::snprintf(end, sizeof end, "%.4f", a.baseline_end_error);
    const bool labelled = a.labelled > 0;
    std::snprintf(line, sizeof line, "%-10s %6d %12.4f %12s %8s %9s %9s %9s\n", name.c_str(),
                  a.scenes, a.model_end_error, end,
                  labelled ? std::to_string(a.labelled).c_str() : "-",
                  labelled ? percent(a.model_accuracy).c_str() : "-",
                  labelled && baseline ? percent(a.baseline_accuracy).c_str() : "-",
                  labelled ? percent(a.truth_accuracy).c_str() : "-");
    out += line;
  }
  if (s.contact.scenarios >= 2) {
    std::snprintf(line, sizeof line, "%-10s %6s %12s %12s %8s %9s %9s %9s  (%d scenarios)\n",
                  "mean", "", "", "", "", percent(s.contact.model).c_str(),
                  baseline ? percent(s.contact.baseline).c_str() : "-",
                  percent(s.contact.truth).c_str(), s.contact.scenarios);
    out += line;
  }
  return out;
}

}  // namespace dynscope
