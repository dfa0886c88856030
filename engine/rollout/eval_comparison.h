// Comparing evaluations of several runs over seeds: mean ± sd of each run's end error and contact
// accuracy over its seeds, and paired per-scene differences between runs (what a claim such as
// "PointConv U-Net < GNN U-Net" rests on). Reads the files `dynscope eval --json` writes.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "engine/rollout/evaluation.h"

namespace dynscope {

/// One run: the evaluations of its seeds (same split, same scenes), under a label.
struct RunEvaluations {
  std::string label;
  std::vector<std::string> paths;  ///< Where each seed's evaluation was read from.
  std::vector<EvalSummary> seeds;
};

/// A run's numbers over its seeds (sample standard deviation; 0 for one seed).
struct RunStats {
  std::string label;
  int seeds = 0;
  double end_error_mean = 0.0, end_error_sd = 0.0;
  /// The constant-velocity baseline's end error on this run's own points (the first of its
  /// evaluations that has it; NaN if none): runs on other points (mesh vertices against surface
  /// samples) have other floors.
  double floor_end_error = 0.0;
  int labelled = 0;  ///< Scenes with a contact label (0: no contact accuracy).
  /// Contact accuracy (each evaluation's mean over its scenarios, ContactMean) over seeds.
  double accuracy_mean = 0.0, accuracy_sd = 0.0;
  /// Per scenario of EvalComparison::contact_scenarios: contact accuracy over seeds.
  std::vector<double> scenario_accuracy_mean, scenario_accuracy_sd;
};

/// Run A against run B scene by scene: each scene's end error averaged over each run's seeds,
/// then the difference A − B averaged over scenes with its standard error.
struct PairedDifference {
  std::string a, b;
  int scenes = 0;
  double mean = 0.0;       ///< Mean over scenes of A − B (negative: A is better).
  double std_error = 0.0;  ///< Standard error of that mean (sample sd / √scenes).
  int a_better = 0;        ///< Scenes where A's end error is lower.
  /// Whether the seed intervals (mean ± sd over seeds) of A and B overlap; unknown (nullopt)
  /// unless both runs have at least two seeds.
  std::optional<bool> seed_intervals_overlap;
};

/// Everything compare_evaluations finds.
struct EvalComparison {
  std::string split;
  int scenes = 0;
  /// The constant-velocity baseline's end error in the first evaluation that has it (NaN if none
  /// has); each run's own is RunStats::floor_end_error.
  double floor_end_error = 0.0;
  double floor_accuracy = 0.0;  ///< Its contact accuracy (NaN if no scene is labelled).
  double truth_accuracy = 0.0;  ///< The threshold rule on the ground truth (NaN likewise).
  /// The labelled scenarios when there are two or more (the Physion table shape), with the
  /// floor's and the ceiling's accuracy in each.
  std::vector<std::string> contact_scenarios;
  std::vector<double> floor_scenario_accuracy, truth_scenario_accuracy;
  std::vector<RunStats> runs;
  std::vector<PairedDifference> pairs;  ///< Every pair (i < j) of runs, in the order given.
};

/// Compares `runs` (at least one, each with at least one seed). Every evaluation must cover the
/// same split and the same scene files (in any order); throws ValueError naming the files that
/// differ otherwise.
EvalComparison compare_evaluations(const std::vector<RunEvaluations>& runs);

/// The comparison as plain-text tables.
std::string comparison_table(const EvalComparison& c);
/// The comparison as indented JSON.
std::string comparison_to_json(const EvalComparison& c);

}  // namespace dynscope
