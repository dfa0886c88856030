// Dataset evaluation: Kubric-style end-of-rollout point error and Physion-style contact accuracy,
// for a model and the constant-velocity-plus-gravity baseline.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "engine/core/progress.h"
#include "engine/rollout/dataset_split.h"
#include "engine/rollout/metrics.h"
#include "engine/rollout/model_points.h"
#include "engine/rollout/rollout_runner.h"

namespace dynscope {

/// What an evaluation runs.
struct EvalOptions {
  int observed_frames = 3;         ///< Ground-truth frames before prediction starts.
  SamplingOptions sampling;        ///< Model points (input mode must match the model).
  double contact_threshold = 0.0;  ///< Contact distance (scene units); 0: fraction × voxel.
  double threshold_fraction = kContactThresholdFraction;  ///< Used when contact_threshold is 0.
  /// Per scenario: the contact threshold as this fraction of the sampling voxel, in place of
  /// contact_threshold and threshold_fraction for that scenario's scenes (the Physion protocol
  /// uses 1.5 × the spacing but 1.0 × in contain and drop).
  std::map<std::string, double> scenario_threshold_fraction;
  bool baseline = true;  ///< Also roll out the constant-velocity baseline.
};

/// The contact distance (scene units) `options` give the scenes of `scenario` sampled at `voxel`.
double contact_threshold_for(const EvalOptions& options, const std::string& scenario, double voxel);

/// Results of one scene.
struct SceneEvaluation {
  std::string file;
  std::string scenario;
  int frames = 0;
  int label = -1;  ///< Scene label (any frame of target_contacting_zone), −1 none.
  std::vector<double> model_curve;  ///< `[T]` mean point error per frame.
  std::vector<double> baseline_curve;
  bool has_contact = false;    ///< The scene has a target and a zone.
  bool truth_contact = false;  ///< Threshold rule applied to the ground-truth points.
  bool model_contact = false;
  bool baseline_contact = false;
  double model_min_distance = 0.0;  ///< Min target–zone distance over all frames.
  double baseline_min_distance = 0.0;
  double truth_min_distance = 0.0;
};

/// Aggregates of one scenario (or of everything, scenario "all").
struct ScenarioSummary {
  int scenes = 0;
  double model_end_error = 0.0;  ///< Mean over scenes of the last frame's point error.
  double baseline_end_error = 0.0;
  std::vector<double> model_curve;  ///< Mean per-frame error over scenes (shortest length).
  std::vector<double> baseline_curve;
  int labelled = 0;             ///< Scenes with a label and a target and zone.
  double model_accuracy = 0.0;  ///< Fraction of labelled scenes predicted right.
  double baseline_accuracy = 0.0;
  double truth_accuracy = 0.0;  ///< The threshold rule on ground truth (its ceiling).
};

/// Contact accuracy as the Physion benchmark averages it: the unweighted mean over the scenarios
/// that have labelled scenes (for one such scenario, or equal counts, the same as "all").
struct ContactMean {
  int scenarios = 0;  ///< Scenarios with labelled scenes (0: no contact accuracy).
  double model = 0.0, baseline = 0.0, truth = 0.0;
};

/// The whole evaluation.
struct EvalSummary {
  std::string dir, split;
  int observed_frames = 0;
  double voxel = 0.0;      ///< Sampling voxel of the model points.
  double threshold = 0.0;  ///< Contact threshold used (scene units).
  /// The scenarios evaluated with a threshold of their own
  /// (EvalOptions::scenario_threshold_fraction) and that threshold (scene units).
  std::map<std::string, double> scenario_thresholds;
  std::vector<SceneEvaluation> scenes;
  std::map<std::string, ScenarioSummary> scenarios;  ///< Per scenario, plus "all".
  ContactMean contact;  ///< Mean contact accuracy over the scenarios (the headline number).
};

/// The physics-free floor of every comparison: constant velocity plus the scenario's gravity,
/// Kabsch-rigidified, clamped at the floor z = 0, rolled out like a model (`options` as given,
/// floor clamp forced on).
Rollout run_baseline_rollout(const Scene& scene, const ModelPoints& points, RolloutOptions options);
/// One line naming the baseline, for tables and JSON.
extern const char* const kBaselineDescription;

/// Rolls out `model` (and the baseline) on every scene of `split`, reporting each scene to
/// `progress`. Throws like read_scene, build_model_points and run_rollout (the message names the
/// scene file).
EvalSummary evaluate_split(const DatasetSplit& split, const StepPredictor& model,
                           const EvalOptions& options, Progress* progress = nullptr);

/// One scene of a split, as evaluate_split does it; `voxel` and `threshold` (may be null) receive
/// the sampling voxel and the contact threshold of scenes without one of their own (the scene's
/// own is contact_threshold_for(options, its scenario, voxel)). Throws like evaluate_split.
SceneEvaluation evaluate_scene(const DatasetItem& item, const StepPredictor& model,
                               const EvalOptions& options, double* voxel, double* threshold);

/// The summary of `scenes` (in split order) evaluated with `options`, `voxel` and `threshold`:
/// what evaluate_split returns (data-parallel evaluation gathers the scenes of every rank).
EvalSummary summarize_evaluation(const DatasetSplit& split, const EvalOptions& options,
                                 std::vector<SceneEvaluation> scenes, double voxel,
                                 double threshold);

/// One scene's results as compact JSON and back (exact: doubles round-trip). The reader throws
/// FormatError for anything else.
std::string scene_evaluation_to_json(const SceneEvaluation& e);
SceneEvaluation scene_evaluation_from_json(const std::string& text);

/// The summary as indented JSON (every number, per scene and per scenario).
std::string eval_to_json(const EvalSummary& summary);
/// Reads a file eval_to_json wrote (`dynscope eval --json`) back: every scene's curves and
/// contact outcomes, and the per-scenario summary recomputed from them. Throws IoError if the
/// file cannot be read, FormatError naming the field for anything malformed.
EvalSummary read_eval_json(const std::string& path);

/// A plain-text table of the per-scenario summary (with a "mean" row of the scenarios' contact
/// accuracy when two or more scenarios are labelled).
std::string eval_table(const EvalSummary& summary);

}  // namespace dynscope
