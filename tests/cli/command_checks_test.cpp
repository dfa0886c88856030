// Tests of the commands' checks: options outside their range and outputs that would overwrite an
// input are refused with one line naming the option and the accepted range, before any work.
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/support/read_file.h"
#include "tests/support/run_command.h"

namespace dynscope {
namespace {

namespace fs = std::filesystem;
using test::run_dynscope;

const std::string kSource = DYNSCOPE_SOURCE_DIR;
const std::string kScene = kSource + "/assets/scenes/movi-a_0000.h5";
const std::string kCheckpoint = kSource + "/assets/models/movi-a_pointconv_acc.pt";

using test::read_bytes;

// A scratch directory holding copies of the bundled scene and checkpoint.
class CommandChecks : public ::testing::Test {
 protected:
  void SetUp() override {
    static std::atomic<int> counter{0};
    dir_ = fs::temp_directory_path() /
           ("dynscope-checks-" + std::to_string(getpid()) + "-" + std::to_string(counter++));
    fs::create_directories(dir_);
    scene_ = (dir_ / "scene.h5").string();
    checkpoint_ = (dir_ / "model.pt").string();
    fs::copy_file(kScene, scene_);
    fs::copy_file(kCheckpoint, checkpoint_);
    scene_bytes_ = read_bytes(scene_);
    checkpoint_bytes_ = read_bytes(checkpoint_);
  }
  void TearDown() override {
    EXPECT_EQ(read_bytes(scene_), scene_bytes_) << "the scene input was modified";
    EXPECT_EQ(read_bytes(checkpoint_), checkpoint_bytes_) << "the checkpoint input was modified";
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }

  // Runs `args`, expects a failure whose one-line message holds every part of `parts`.
  void expect_refused(const std::string& args, std::initializer_list<std::string> parts) {
    const auto r = run_dynscope(args);
    EXPECT_NE(r.exit_code, 0) << args << "\n" << r.output;
    EXPECT_NE(r.exit_code, -1) << args << " was killed by a signal";
    for (const std::string& part : parts) {
      EXPECT_NE(r.output.find(part), std::string::npos)
          << "'" << part << "' not in the output of " << args << ":\n"
          << r.output;
    }
    const std::string text = r.output.substr(0, r.output.find_last_not_of('\n') + 1);
    EXPECT_EQ(text.find('\n'), std::string::npos) << args << ": not one line:\n" << r.output;
  }

  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  // A dataset directory "data": the bundled movi-a manifest and its two scenes.
  void make_dataset() const {
    fs::create_directories(path("data"));
    fs::copy_file(kSource + "/assets/scenes/movi-a_manifest.json", path("data/manifest.json"));
    for (const char* scene : {"movi-a_0000.h5", "movi-a_0001.h5"}) {
      fs::copy_file(kSource + "/assets/scenes/" + scene, path(std::string("data/") + scene));
    }
  }

  fs::path dir_;
  std::string scene_, checkpoint_, scene_bytes_, checkpoint_bytes_;
};

TEST_F(CommandChecks, OutputsThatWouldOverwriteAnInputAreRefused) {
  const std::string rollout = "rollout --checkpoint " + checkpoint_ + " --scene " + scene_;
  expect_refused(rollout + " --out " + scene_, {"--out", "--scene", "destroy"});
  expect_refused(rollout + " --out " + checkpoint_, {"--out", "--checkpoint"});
  // The same file under another name: a symbolic link and a path with "..".
  fs::create_symlink(scene_, path("link.h5"));
  expect_refused(rollout + " --out " + path("link.h5"), {"--out", "--scene"});
  fs::create_directories(path("sub"));
  expect_refused(rollout + " --out " + path("sub/../scene.h5"), {"--out", "--scene"});
  expect_refused("trace --checkpoint " + checkpoint_ + " --scene " + scene_ + " --out " + scene_,
                 {"--out", "--scene"});
  expect_refused("view " + scene_ + " --screenshot " + scene_, {"--screenshot", "file"});
  make_dataset();
  const std::string eval =
      "eval --checkpoint " + checkpoint_ + " --data " + path("data") + " --split all --json ";
  expect_refused(eval + checkpoint_, {"--json", "--checkpoint"});
  expect_refused(eval + path("data/manifest.json"), {"--json", "dataset manifest"});
  expect_refused(eval + path("data/movi-a_0001.h5"), {"--json", "dataset scene"});
}

// `eval --max-scenes N` evaluates N scenes of the split, evenly spaced, and says so; a negative
// count is refused.
TEST_F(CommandChecks, EvalMaxScenesSamplesTheSplitAndSaysSo) {
  make_dataset();
  const std::string eval = "eval --checkpoint " + checkpoint_ + " --data " + path("data") +
                           " --split all --no-baseline --threads 1";
  expect_refused(eval + " --max-scenes -1", {"--max-scenes"});
  const auto r = run_dynscope(eval + " --max-scenes 1 --json " + path("one.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("split all, 1 of 2 evenly spaced"), std::string::npos) << r.output;
  const std::string json = read_bytes(path("one.json"));
  EXPECT_NE(json.find("movi-a_0000.h5"), std::string::npos) << json;
  EXPECT_EQ(json.find("movi-a_0001.h5"), std::string::npos) << "only the first of two scenes";
}

// `eval --data A B` evaluates the scenarios of several directories as one set: contact accuracy
// per scenario and their mean, which `compare` reads back with a per-scenario table.
TEST_F(CommandChecks, EvalOfSeveralScenarioDirectoriesGivesTheMeanOverScenarios) {
  for (const char* scenario : {"collide", "roll"}) {
    const std::string dir = path(scenario);
    fs::create_directories(dir);
    fs::copy_file(kSource + "/assets/scenes/" + scenario + "_manifest.json",
                  dir + "/manifest.json");
    for (const char* i : {"_0000.h5", "_0001.h5"}) {
      fs::copy_file(kSource + "/assets/scenes/" + scenario + i, dir + "/" + scenario + i);
    }
  }
  const std::string eval = "eval --checkpoint " + kSource +
                           "/assets/models/physion_pointconv_acc.pt --split all --threads 1";
  expect_refused(eval + " --data " + path("collide") + " " + path("collide"),
                 {"data", "named twice"});
  const auto r = run_dynscope(eval + " --data " + path("collide") + " " + path("roll") +
                              " --json " + path("both.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("(2 scenarios)"), std::string::npos) << r.output;
  const nlohmann::json j = nlohmann::json::parse(read_bytes(path("both.json")));
  ASSERT_EQ(j.at("scenes").size(), 4u);
  const double collide = j.at("scenarios").at("collide").at("contact_accuracy").get<double>();
  const double roll = j.at("scenarios").at("roll").at("contact_accuracy").get<double>();
  EXPECT_DOUBLE_EQ(j.at("contact_scenario_mean").at("contact_accuracy").get<double>(),
                   (collide + roll) / 2);
  EXPECT_EQ(j.at("contact_scenario_mean").at("scenarios"), 2);
  const auto c = run_dynscope("compare model=" + path("both.json"));
  ASSERT_EQ(c.exit_code, 0) << c.output;
  EXPECT_NE(c.output.find("per scenario"), std::string::npos) << c.output;
  EXPECT_NE(c.output.find("collide"), std::string::npos) << c.output;

  // A threshold of roll's own (the Physion protocol's form): every scene's three contact
  // decisions follow its closest approach and its scenario's threshold.
  const std::string both = " --data " + path("collide") + " " + path("roll");
  const std::string own = " --scenario-threshold-fraction ";
  expect_refused(eval + both + own + "roll",
                 {"--scenario-threshold-fraction", "SCENARIO=FRACTION"});
  expect_refused(eval + both + own + "roll=x", {"SCENARIO=FRACTION", "'roll=x'"});
  expect_refused(eval + both + own + "nope=1", {"unknown scenario 'nope'"});
  expect_refused(eval + both + own + "roll=0", {"--scenario-threshold-fraction"});
  expect_refused(eval + both + own + "roll=1" + own + "roll=2", {"roll is named twice"});
  const auto t = run_dynscope(eval + both + " --threshold-fraction 1.5" + own + "roll=1 --json " +
                              path("own.json"));
  ASSERT_EQ(t.exit_code, 0) << t.output;
  EXPECT_NE(t.output.find("contact threshold 0.075 (roll 0.05)"), std::string::npos) << t.output;
  const nlohmann::json o = nlohmann::json::parse(read_bytes(path("own.json")));
  EXPECT_DOUBLE_EQ(o.at("contact_threshold").get<double>(), 0.075);
  EXPECT_DOUBLE_EQ(o.at("scenario_contact_thresholds").at("roll").get<double>(), 0.05);
  EXPECT_EQ(o.at("scenario_contact_thresholds").size(), 1u);
  for (const nlohmann::json& e : o.at("scenes")) {
    const double threshold = e.at("scenario") == "roll" ? 0.05 : 0.075;
    for (const char* who : {"", "truth_", "baseline_"}) {
      EXPECT_EQ(e.at(std::string(who) + "contact").get<bool>(),
                e.at(std::string(who) + "min_distance").get<double>() < threshold)
          << e.at("file") << " " << who;
    }
  }
}

// An output into a directory that does not exist is refused before any work (one line, no
// progress bar), not after a whole rollout or training run.
TEST_F(CommandChecks, OutputsIntoAMissingDirectoryAreRefusedBeforeAnyWork) {
  const std::string missing = path("no_such_dir");
  expect_refused(
      "rollout --checkpoint " + checkpoint_ + " --scene " + scene_ + " --out " + missing + "/r.h5",
      {"--out", "no_such_dir", "does not exist"});
  expect_refused(
      "trace --checkpoint " + checkpoint_ + " --scene " + scene_ + " --out " + missing + "/t.h5",
      {"--out", "does not exist"});
  expect_refused("view " + scene_ + " --screenshot " + missing + "/shot.png",
                 {"--screenshot", "does not exist"});
  expect_refused("train --recipe " + kCheckpoint + ".recipe.json --data " + path("data") +
                     " --out " + missing + "/model.pt",
                 {"--out", "does not exist"});
  fs::create_directories(path("a_directory.h5"));
  expect_refused("rollout --checkpoint " + checkpoint_ + " --scene " + scene_ + " --out " +
                     path("a_directory.h5"),
                 {"--out", "is a directory"});
}

TEST_F(CommandChecks, RenderRefusesAnInputInsideItsOutputUnderAnOutputName) {
  fs::create_directories(path("out"));
  for (const char* name : {"frame_0000.png", "view.json", "contact_sheet.png"}) {
    const std::string input = path(std::string("out/") + name);
    fs::copy_file(scene_, input, fs::copy_options::overwrite_existing);
    const std::string before = read_bytes(input);
    expect_refused("render " + input + " --out " + path("out") + " --no-video",
                   {"--out", "output directory"});
    EXPECT_EQ(read_bytes(input), before) << name;
  }
  expect_refused("render " + scene_ + " --out " + scene_, {"--out", "input"});
}

TEST_F(CommandChecks, CompareRefusesMismatchedMalformedOrOverwrittenEvaluations) {
  auto write_eval = [this](const std::string& name, const std::string& scene, double end) {
    std::ofstream(path(name)) << R"({"dir":"d","split":"test","observed_frames":3,)"
                              << R"("sampling_voxel":0.3,"contact_threshold":0.3,"scenes":[)"
                              << R"({"file":")" << scene << R"(","scenario":"movi-a","frames":2,)"
                              << R"("label":-1,"error_curve":[0,)" << end
                              << R"(],"baseline_error_curve":[0,4]}]})";
  };
  write_eval("a.json", "s0.h5", 1.0);
  write_eval("b.json", "s0.h5", 2.0);
  write_eval("other.json", "s9.h5", 2.0);
  const auto ok = run_dynscope("compare A=" + path("a.json") + " B=" + path("b.json") + " --json " +
                               path("c.json"));
  EXPECT_EQ(ok.exit_code, 0) << ok.output;
  EXPECT_NE(ok.output.find("-1.0000 ± 0.0000"), std::string::npos) << ok.output;
  EXPECT_TRUE(fs::exists(path("c.json")));
  expect_refused("compare A=" + path("a.json") + " B=" + path("other.json"), {"s9.h5"});
  expect_refused("compare A=" + path("a.json") + " --json " + path("a.json"),
                 {"--json", "evaluation of A"});
  expect_refused("compare A=" + path("a.json") + "," + path("missing.json"), {"missing.json"});
  expect_refused("compare A=" + scene_, {"scene.h5"});
  expect_refused("compare =" + path("a.json"), {"label"});
}

TEST_F(CommandChecks, OptionsOutsideTheirRangeNameTheRange) {
  const std::string rollout =
      "rollout --checkpoint " + checkpoint_ + " --scene " + scene_ + " --out " + path("r.h5");
  expect_refused(rollout + " --voxel 0", {"--voxel", "(0, "});
  expect_refused(rollout + " --voxel -0.3", {"--voxel", "got -0.3"});
  expect_refused(rollout + " --voxel nan", {"--voxel"});
  expect_refused(rollout + " --frames -1", {"--frames", "[0, 1000000]"});
  expect_refused(rollout + " --threads 100000", {"--threads", "[0, 1024]"});
  expect_refused(rollout + " --observed 2", {"--observed", "[3, "});
  EXPECT_FALSE(fs::exists(path("r.h5")));

  const std::string render = "render " + scene_ + " --out " + path("frames") + " --no-video";
  expect_refused(render + " --level -1", {"--level", "[0, 7]"});
  expect_refused(render + " --level 99", {"--level", "got 99"});
  expect_refused(render + " --pick -2", {"--pick", "[0, "});
  expect_refused(render + " --samples -1", {"--samples", "[0, 64]"});
  EXPECT_FALSE(fs::exists(path("frames")));

  expect_refused("trace --checkpoint " + checkpoint_ + " --scene " + scene_ + " --out " +
                     path("t.h5") + " --query 3,-2",
                 {"--query", "-2"});
  expect_refused("generate --scenario drop --count 0 --out " + path("gen"), {"count", "[1, "});
  expect_refused("generate --scenario drop --count 2 --jobs 100000 --out " + path("gen"),
                 {"jobs", "[1, 1024]"});
  expect_refused("generate --scenario drop --count 2 --mesh-density coarse --out " + path("gen"),
                 {"--mesh-density", "coarse", "dense", "sparse"});
}

}  // namespace
}  // namespace dynscope
