// Comparing evaluations: eval JSON read back exactly, mean ± sd over seeds, paired per-scene
// differences against a hand computation, and clear errors for files that do not match.
#include "engine/rollout/eval_comparison.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>

#include "engine/core/error.h"
#include "engine/io/temp_file.h"

namespace dynscope {
namespace {

namespace fs = std::filesystem;

fs::path temp_dir() {
  const fs::path dir =
      fs::temp_directory_path() / ("dynscope_eval_comparison_" + std::to_string(getpid()));
  fs::create_directories(dir);
  return dir;
}

// A scene whose model error grows linearly to `end` over 4 frames; labelled scenes get contacts.
SceneEvaluation scene(const std::string& file, double end, int label = -1, bool contact = false) {
  SceneEvaluation e;
  e.file = file;
  e.scenario = label >= 0 ? "collide" : "movi-a";
  e.frames = 4;
  e.label = label;
  e.model_curve = {0.0, end / 3, 2 * end / 3, end};
  e.baseline_curve = {0.0, 1.0, 2.0, 3.0};
  if (label >= 0) {
    e.has_contact = true;
    e.model_contact = contact;
    e.truth_contact = label == 1;
    e.baseline_contact = false;
    e.model_min_distance = contact ? 0.01 : 0.5;
    e.truth_min_distance = label == 1 ? 0.02 : 0.6;
    e.baseline_min_distance = 0.7;
  }
  return e;
}

// Writes an evaluation of `scenes` as `dynscope eval --json` does and returns its path.
std::string write_eval(const std::string& name, std::vector<SceneEvaluation> scenes) {
  DatasetSplit split;
  split.dir = "data/x";
  split.split = "test";
  EvalOptions options;
  const EvalSummary s = summarize_evaluation(split, options, std::move(scenes), 0.3, 0.3);
  const std::string path = (temp_dir() / (name + ".json")).string();
  write_text_file_atomically(path, eval_to_json(s));
  return path;
}

RunEvaluations run(const std::string& label, const std::vector<std::string>& paths) {
  RunEvaluations r;
  r.label = label;
  r.paths = paths;
  for (const std::string& p : paths) r.seeds.push_back(read_eval_json(p));
  return r;
}

TEST(EvalComparison, ReadsAnEvaluationBackExactly) {
  const std::vector<SceneEvaluation> scenes = {scene("a.h5", 1.0 / 3.0, 1, true),
                                               scene("b.h5", 2.5, 0, true), scene("c.h5", 0.7)};
  const EvalSummary back = read_eval_json(write_eval("roundtrip", scenes));
  EXPECT_EQ(back.split, "test");
  EXPECT_EQ(back.dir, "data/x");
  EXPECT_DOUBLE_EQ(back.voxel, 0.3);
  ASSERT_EQ(back.scenes.size(), 3u);
  for (size_t i = 0; i < scenes.size(); ++i) {
    EXPECT_EQ(back.scenes[i].file, scenes[i].file);
    EXPECT_EQ(back.scenes[i].model_curve, scenes[i].model_curve) << "doubles round-trip";
    EXPECT_EQ(back.scenes[i].baseline_curve, scenes[i].baseline_curve);
    EXPECT_EQ(back.scenes[i].has_contact, scenes[i].has_contact);
    EXPECT_EQ(back.scenes[i].model_contact, scenes[i].model_contact);
    EXPECT_EQ(back.scenes[i].truth_min_distance, scenes[i].truth_min_distance);
  }
  const ScenarioSummary& all = back.scenarios.at("all");
  EXPECT_EQ(all.labelled, 2);
  EXPECT_DOUBLE_EQ(all.model_accuracy, 0.5);  // a: contact and label 1; b: contact, label 0
  EXPECT_DOUBLE_EQ(all.model_end_error, (1.0 / 3.0 + 2.5 + 0.7) / 3.0);
}

// A scenario's own threshold (EvalOptions::scenario_threshold_fraction) is summarised in scene
// units, named in the table and read back.
TEST(EvalComparison, AScenariosOwnThresholdIsKeptAndReadBack) {
  DatasetSplit split;
  split.dir = "data/x";
  split.split = "all";
  EvalOptions options;
  options.threshold_fraction = 1.5;
  options.scenario_threshold_fraction = {{"collide", 1.0}, {"drop", 2.0}};  // no drop scene
  EXPECT_DOUBLE_EQ(contact_threshold_for(options, "collide", 0.3), 0.3);
  EXPECT_DOUBLE_EQ(contact_threshold_for(options, "roll", 0.3), 0.45);
  options.contact_threshold = 0.2;  // an absolute threshold does not replace a scenario's own
  EXPECT_DOUBLE_EQ(contact_threshold_for(options, "collide", 0.3), 0.3);
  EXPECT_DOUBLE_EQ(contact_threshold_for(options, "roll", 0.3), 0.2);
  const EvalSummary s = summarize_evaluation(
      split, options, {scene("a.h5", 1.0, 1, true), scene("b.h5", 2.0)}, 0.3, 0.2);
  const std::map<std::string, double> expected = {{"collide", 0.3}};
  EXPECT_EQ(s.scenario_thresholds, expected) << "only scenarios that have scenes";
  EXPECT_NE(eval_table(s).find("contact threshold 0.2 (collide 0.3)"), std::string::npos)
      << eval_table(s);
  const std::string path = (temp_dir() / "own_threshold.json").string();
  write_text_file_atomically(path, eval_to_json(s));
  EXPECT_EQ(read_eval_json(path).scenario_thresholds, expected);
}

TEST(EvalComparison, SeedMeansAndPairedDifferencesMatchAHandComputation) {
  // Run A, two seeds; run B, one seed; the same three scenes listed in different orders.
  const std::string a1 =
      write_eval("a1", {scene("s0.h5", 1.0), scene("s1.h5", 2.0), scene("s2.h5", 3.0)});
  const std::string a2 =
      write_eval("a2", {scene("s2.h5", 5.0), scene("s0.h5", 1.0), scene("s1.h5", 4.0)});
  const std::string b1 =
      write_eval("b1", {scene("s1.h5", 2.5), scene("s2.h5", 3.0), scene("s0.h5", 2.0)});
  const EvalComparison c = compare_evaluations({run("A", {a1, a2}), run("B", {b1})});
  EXPECT_EQ(c.scenes, 3);
  EXPECT_DOUBLE_EQ(c.floor_end_error, 3.0);
  EXPECT_TRUE(std::isnan(c.truth_accuracy)) << "no labelled scene";
  ASSERT_EQ(c.runs.size(), 2u);
  // A's seeds end at 2 and 10/3: mean 8/3, sample sd |10/3 - 2| / sqrt(2).
  EXPECT_DOUBLE_EQ(c.runs[0].end_error_mean, 8.0 / 3.0);
  EXPECT_NEAR(c.runs[0].end_error_sd, (4.0 / 3.0) / std::sqrt(2.0), 1e-12);
  EXPECT_DOUBLE_EQ(c.runs[1].end_error_mean, 7.5 / 3.0);
  EXPECT_EQ(c.runs[1].end_error_sd, 0.0);
  // Per scene, A averaged over seeds: s0 1, s1 3, s2 4; B: 2, 2.5, 3. Differences -1, 0.5, 1.
  ASSERT_EQ(c.pairs.size(), 1u);
  const PairedDifference& p = c.pairs[0];
  EXPECT_EQ(p.a, "A");
  EXPECT_EQ(p.b, "B");
  EXPECT_NEAR(p.mean, 0.5 / 3.0, 1e-12);
  const double m = 0.5 / 3.0;
  const double var = ((-1 - m) * (-1 - m) + (0.5 - m) * (0.5 - m) + (1 - m) * (1 - m)) / 2.0;
  EXPECT_NEAR(p.std_error, std::sqrt(var / 3.0), 1e-12);
  EXPECT_EQ(p.a_better, 1);
  EXPECT_FALSE(p.seed_intervals_overlap.has_value()) << "B has one seed: no interval";
  const std::string table = comparison_table(c);
  EXPECT_NE(table.find("2.6667 ± 0.9428"), std::string::npos) << table;
  EXPECT_NE(table.find("A         2    2.6667 ± 0.9428"), std::string::npos)
      << "right-aligned in 18 characters under \"end error\" (± is one)\n"
      << table;
  EXPECT_NE(table.find("+0.1667"), std::string::npos) << table;
  const nlohmann::json j = nlohmann::json::parse(comparison_to_json(c));
  EXPECT_EQ(j.at("pairs").at(0).at("a_better"), 1);
  EXPECT_TRUE(j.at("truth_contact_accuracy").is_null());
  EXPECT_TRUE(j.at("pairs").at(0).at("seed_intervals_overlap").is_null());
  // With two seeds each, intervals are compared: B's 2.5 ± 0.5 against A's 2.67 ± 0.94 overlap.
  const std::string b2 =
      write_eval("b2", {scene("s1.h5", 2.5), scene("s2.h5", 4.5), scene("s0.h5", 2.0)});
  const EvalComparison c2 = compare_evaluations({run("A", {a1, a2}), run("B", {b1, b2})});
  ASSERT_TRUE(c2.pairs[0].seed_intervals_overlap.has_value());
  EXPECT_TRUE(*c2.pairs[0].seed_intervals_overlap);
}

// Runs on other points (mesh vertices against surface samples) have other constant-velocity
// floors: each run's "vs floor" is against its own, and each floor gets its row.
TEST(EvalComparison, EachRunIsSetAgainstTheFloorOnItsOwnPoints) {
  auto on_vertices = [](SceneEvaluation e) {
    e.baseline_curve = {0.0, 2.0, 4.0, 6.0};
    return e;
  };
  const std::string p1 = write_eval("fl_points1", {scene("s0.h5", 1.5), scene("s1.h5", 1.5)});
  const std::string p2 = write_eval("fl_points2", {scene("s0.h5", 1.5), scene("s1.h5", 1.5)});
  const std::string m1 =
      write_eval("fl_mesh1", {on_vertices(scene("s0.h5", 1.5)), on_vertices(scene("s1.h5", 1.5))});
  const std::string m2 =
      write_eval("fl_mesh2", {on_vertices(scene("s0.h5", 3.0)), on_vertices(scene("s1.h5", 3.0))});
  const EvalComparison c =
      compare_evaluations({run("points", {p1, p2}), run("mesh", {m1}), run("mesh2", {m2})});
  EXPECT_DOUBLE_EQ(c.floor_end_error, 3.0) << "the first evaluation's";
  EXPECT_DOUBLE_EQ(c.runs[0].floor_end_error, 3.0);
  EXPECT_DOUBLE_EQ(c.runs[1].floor_end_error, 6.0);
  const std::string table = comparison_table(c);
  EXPECT_NE(table.find("1.5000 ± 0.0000     0.50x"), std::string::npos) << table;
  EXPECT_NE(table.find("1.5000 ± 0.0000     0.25x"), std::string::npos) << table;
  EXPECT_NE(table.find("3.0000 ± 0.0000     0.50x"), std::string::npos) << table;
  EXPECT_NE(table.find("3.0000     1.00x   (constant velocity + gravity; the floor of points)"),
            std::string::npos)
      << table;
  EXPECT_NE(
      table.find("6.0000     1.00x   (constant velocity + gravity; the floor of mesh, mesh2)"),
      std::string::npos)
      << table;
  const nlohmann::json j = nlohmann::json::parse(comparison_to_json(c));
  EXPECT_DOUBLE_EQ(j.at("runs").at(1).at("floor_end_error").get<double>(), 6.0);
  // One floor for every run: one row, as before, without naming the runs.
  const std::string one = comparison_table(compare_evaluations({run("points", {p1, p2})}));
  EXPECT_NE(one.find("3.0000     1.00x   (constant velocity + gravity)\n"), std::string::npos)
      << one;
  // Without the baseline (eval --no-baseline) there is no floor and no ratio.
  std::vector<SceneEvaluation> bare = {scene("s0.h5", 1.5), scene("s1.h5", 1.5)};
  for (SceneEvaluation& e : bare) e.baseline_curve.clear();
  const EvalComparison none = compare_evaluations({run("bare", {write_eval("fl_bare", bare)})});
  EXPECT_TRUE(std::isnan(none.runs[0].floor_end_error));
  EXPECT_EQ(comparison_table(none).find("floor  "), std::string::npos) << comparison_table(none);
}

TEST(EvalComparison, SeparatedRunsAndContactAccuracy) {
  const std::string a = write_eval("ca", {scene("s0.h5", 1.0, 1, true), scene("s1.h5", 1.0, 0)});
  const std::string b = write_eval("cb", {scene("s0.h5", 2.0, 1, false), scene("s1.h5", 3.0, 0)});
  const std::string a2 = write_eval("ca2", {scene("s0.h5", 1.2, 1, true), scene("s1.h5", 1.0, 0)});
  const std::string b2 = write_eval("cb2", {scene("s0.h5", 2.2, 1, false), scene("s1.h5", 3.0, 0)});
  const EvalComparison c = compare_evaluations({run("good", {a, a2}), run("bad", {b, b2})});
  EXPECT_DOUBLE_EQ(c.runs[0].accuracy_mean, 1.0);
  EXPECT_DOUBLE_EQ(c.runs[1].accuracy_mean, 0.5);
  EXPECT_DOUBLE_EQ(c.floor_accuracy, 0.5);  // the baseline never predicts contact
  EXPECT_DOUBLE_EQ(c.truth_accuracy, 1.0);
  EXPECT_EQ(c.pairs[0].a_better, 2);
  EXPECT_EQ(c.pairs[0].seed_intervals_overlap, std::optional<bool>(false));
  EXPECT_NE(comparison_table(c).find("apart"), std::string::npos);
}

// Physion-like: contact accuracy is averaged over scenarios (the benchmark's convention), not
// pooled over scenes, and the comparison gives each scenario's accuracy over seeds.
TEST(EvalComparison, ContactAccuracyIsTheMeanOverScenariosWithAPerScenarioTable) {
  auto in = [](SceneEvaluation e, const std::string& scenario) {
    e.scenario = scenario;
    return e;
  };
  // drop: 3 scenes, 1 right; roll: 1 scene, right. Pooled 2/4, mean over scenarios (1/3 + 1)/2.
  const std::vector<SceneEvaluation> seed1 = {
      in(scene("d0.h5", 1.0, 1, true), "drop"), in(scene("d1.h5", 1.0, 1, false), "drop"),
      in(scene("d2.h5", 1.0, 0, true), "drop"), in(scene("r0.h5", 1.0, 0, false), "roll")};
  // Seed 2: drop 2 of 3 right, roll wrong: mean over scenarios (2/3 + 0)/2.
  const std::vector<SceneEvaluation> seed2 = {
      in(scene("d0.h5", 1.0, 1, true), "drop"), in(scene("d1.h5", 1.0, 1, true), "drop"),
      in(scene("d2.h5", 1.0, 0, true), "drop"), in(scene("r0.h5", 1.0, 0, true), "roll")};
  const EvalSummary s1 = read_eval_json(write_eval("phys1", seed1));
  EXPECT_DOUBLE_EQ(s1.scenarios.at("all").model_accuracy, 0.5);
  EXPECT_EQ(s1.contact.scenarios, 2);
  EXPECT_DOUBLE_EQ(s1.contact.model, (1.0 / 3.0 + 1.0) / 2.0);
  EXPECT_DOUBLE_EQ(s1.contact.baseline, (1.0 / 3.0 + 1.0) / 2.0) << "never predicts contact";
  EXPECT_DOUBLE_EQ(s1.contact.truth, 1.0);
  const std::string table = eval_table(s1);
  EXPECT_NE(table.find("mean"), std::string::npos) << table;
  EXPECT_NE(table.find("66.7%"), std::string::npos) << table;
  EXPECT_NE(table.find("(2 scenarios)"), std::string::npos) << table;
  EXPECT_NE(table.find("66.7%     66.7%    100.0%"), std::string::npos)
      << "mean row: model, baseline, truth\n"
      << table;
  // Without the baseline (eval --no-baseline) its columns say "-", not 0.
  std::vector<SceneEvaluation> bare = seed1;
  for (SceneEvaluation& e : bare) e.baseline_curve.clear();
  const std::string no_baseline = eval_table(read_eval_json(write_eval("phys_bare", bare)));
  EXPECT_EQ(no_baseline.find("0.0000"), std::string::npos) << no_baseline;
  EXPECT_NE(no_baseline.find("66.7%         -    100.0%"), std::string::npos) << no_baseline;

  const EvalComparison c =
      compare_evaluations({run("model", {write_eval("phys1", seed1), write_eval("phys2", seed2)})});
  ASSERT_EQ(c.contact_scenarios, (std::vector<std::string>{"drop", "roll"}));
  const RunStats& r = c.runs.at(0);
  const double m1 = (1.0 / 3.0 + 1.0) / 2.0, m2 = (2.0 / 3.0 + 0.0) / 2.0;
  EXPECT_DOUBLE_EQ(r.accuracy_mean, (m1 + m2) / 2.0);
  EXPECT_NEAR(r.accuracy_sd, std::abs(m1 - m2) / std::sqrt(2.0), 1e-12);
  EXPECT_DOUBLE_EQ(r.scenario_accuracy_mean.at(0), 0.5);  // drop: 1/3 and 2/3
  EXPECT_NEAR(r.scenario_accuracy_sd.at(0), (1.0 / 3.0) / std::sqrt(2.0), 1e-12);
  EXPECT_DOUBLE_EQ(r.scenario_accuracy_mean.at(1), 0.5);  // roll: 1 and 0
  EXPECT_DOUBLE_EQ(c.floor_scenario_accuracy.at(0), 1.0 / 3.0);
  EXPECT_DOUBLE_EQ(c.floor_scenario_accuracy.at(1), 1.0);
  EXPECT_DOUBLE_EQ(c.floor_accuracy, m1);
  EXPECT_DOUBLE_EQ(c.truth_scenario_accuracy.at(1), 1.0);
  const std::string compared = comparison_table(c);
  EXPECT_NE(compared.find("mean over 2 scenarios"), std::string::npos) << compared;
  EXPECT_NE(compared.find("50.0 ± 23.6"), std::string::npos) << compared;
  EXPECT_NE(compared.find("50.0 ± 70.7"), std::string::npos) << compared;
  const nlohmann::json j = nlohmann::json::parse(comparison_to_json(c));
  EXPECT_DOUBLE_EQ(
      j.at("runs").at(0).at("scenario_contact_accuracy").at("roll").at("sd").get<double>(),
      std::sqrt(0.5));
  EXPECT_DOUBLE_EQ(j.at("scenario_floor_contact_accuracy").at("roll").get<double>(), 1.0);

  // One scenario: no per-scenario table; the mean is that scenario's accuracy.
  const EvalComparison one = compare_evaluations(
      {run("one", {write_eval("ca_one", {scene("s0.h5", 1.0, 1, true), scene("s1.h5", 1.0, 0)})})});
  EXPECT_TRUE(one.contact_scenarios.empty());
  EXPECT_EQ(comparison_table(one).find("per scenario"), std::string::npos);
}

// The same scene file must be the same scene in every evaluation: scenario and label included.
TEST(EvalComparison, ASceneWithAnotherScenarioOrLabelIsAClearError) {
  SceneEvaluation moved = scene("s0.h5", 1.0, 1, true);
  moved.scenario = "drop";
  const std::string a = write_eval("lab_a", {scene("s0.h5", 1.0, 1, true), scene("s1.h5", 1.0, 0)});
  const std::string b = write_eval("lab_b", {moved, scene("s1.h5", 1.0, 0)});
  const std::string c = write_eval("lab_c", {scene("s0.h5", 1.0, 0, true), scene("s1.h5", 1.0, 0)});
  for (const std::string& other : {b, c}) {
    try {
      compare_evaluations({run("A", {a, other})});
      FAIL() << other;
    } catch (const ValueError& e) {
      EXPECT_NE(std::string(e.what()).find("s0.h5"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("scenario or contact label"), std::string::npos);
    }
  }
}

TEST(EvalComparison, FilesOfOtherScenesOrMalformedFilesAreClearErrors) {
  const std::string a = write_eval("ea", {scene("s0.h5", 1.0), scene("s1.h5", 2.0)});
  const std::string fewer = write_eval("eb", {scene("s0.h5", 1.0)});
  const std::string other = write_eval("ec", {scene("s0.h5", 1.0), scene("s9.h5", 2.0)});
  EXPECT_THROW(compare_evaluations({run("a", {a}), run("b", {fewer})}), ValueError);
  try {
    compare_evaluations({run("a", {a}), run("c", {other})});
    ADD_FAILURE() << "scenes of another split were compared";
  } catch (const ValueError& e) {
    EXPECT_NE(std::string(e.what()).find("s9.h5"), std::string::npos) << e.what();
  }
  EXPECT_THROW(compare_evaluations({}), ValueError);
  const fs::path bad = temp_dir() / "bad.json";
  std::ofstream(bad) << R"({"dir":"d","split":"test","observed_frames":3,"sampling_voxel":0.3,
                           "contact_threshold":0.3,"scenes":[{"file":"a.h5"}]})";
  try {
    read_eval_json(bad.string());
    ADD_FAILURE() << "a scene without curves was read";
  } catch (const FormatError& e) {
    EXPECT_EQ(e.field(), "scenes");
  }
  std::ofstream(temp_dir() / "notjson.json") << "{";
  EXPECT_THROW(read_eval_json((temp_dir() / "notjson.json").string()), FormatError);
  EXPECT_THROW(read_eval_json((temp_dir() / "missing.json").string()), IoError);
}

}  // namespace
}  // namespace dynscope
