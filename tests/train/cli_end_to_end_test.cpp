// generate → train (few steps) → rollout → eval → trace through the built dynscope binary.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>

#include "engine/io/rollout_file.h"
#include "engine/io/trace_file.h"
#include "tests/support/run_command.h"

namespace dynscope {
namespace {

namespace fs = std::filesystem;

int run(const std::string& args) {
  return test::run_dynscope("--log-level warn " + args).exit_code;
}

// `dynscope info --json FILE` must recognise each output file's kind.
std::string info_kind(const std::string& file) {
  const test::CommandResult r = test::run_dynscope("info --json " + file);
  if (r.exit_code != 0) return "error: " + r.output;
  return nlohmann::json::parse(r.output).value("kind", "");
}

TEST(CliEndToEndTest, GenerateTrainRolloutEvalTrace) {
  const fs::path dir = fs::temp_directory_path() / ("dynscope_cli_e2e_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string data = (dir / "data").string();
  const std::string ckpt = (dir / "model.pt").string();
  ASSERT_EQ(run("generate --scenario collide --count 10 --seed 1 --out " + data), 0);
  ASSERT_EQ(run("train --data " + data + " --model pointconv --target acc --out " + ckpt +
                " --max-steps 3 --width 8 --levels 2 --bottleneck-blocks 1 --k 6 --c-mid 4"
                " --sample-voxel 0.1 --val-scenes 1 --val-frames 5 --threads 2 --huber-delta 1000"
                " --log " +
                (dir / "log.csv").string()),
            0);
  EXPECT_TRUE(fs::exists(dir / "log.csv"));
  {
    std::ifstream recipe(ckpt + ".recipe.json");
    EXPECT_EQ(nlohmann::json::parse(recipe).at("huber_delta").get<double>(), 1000.0)
        << "the resolved recipe records the loss it trained with";
  }
  const std::string scene = (fs::path(data) / "collide_0009.h5").string();
  const std::string rollout = (dir / "rollout.h5").string();
  ASSERT_EQ(run("rollout --checkpoint " + ckpt + " --scene " + scene + " --out " + rollout), 0);
  const Rollout r = read_rollout(rollout);
  EXPECT_EQ(r.observed_frames, 3);
  EXPECT_EQ(r.checkpoint_path, ckpt);
  EXPECT_TRUE(r.has_contact());
  const std::string json = (dir / "eval.json").string();
  ASSERT_EQ(run("eval --checkpoint " + ckpt + " --data " + data + " --json " + json), 0);
  EXPECT_TRUE(fs::exists(json));
  const std::string trace = (dir / "trace.h5").string();
  ASSERT_EQ(run("trace --checkpoint " + ckpt + " --scene " + scene +
                " --frame 4 --query 0,3 --out " + trace),
            0);
  const ModelTrace t = read_trace(trace);
  EXPECT_EQ(t.levels.size(), 2u);
  EXPECT_FALSE(t.queries.empty());
  EXPECT_EQ(t.source, kTraceSourceScene);
  // The pass that predicted frame 5 of the rollout, from the rollout's own frames 2..4.
  const std::string rollout_trace = (dir / "rollout_trace.h5").string();
  ASSERT_EQ(run("trace --checkpoint " + ckpt + " --rollout " + rollout +
                " --frame 4 --query 3"
                " --out " +
                rollout_trace),
            0);
  const ModelTrace rt = read_trace(rollout_trace);
  EXPECT_EQ(rt.source, kTraceSourceRollout);
  EXPECT_EQ(rt.rollout_path, rollout);
  EXPECT_EQ(rt.scene_path, r.scene_path);
  EXPECT_EQ(rt.frame, 4);
  EXPECT_EQ(rt.levels[0].points, r.predicted[4]) << "the model read its own prediction";
  EXPECT_NE(rt.levels[0].points, r.truth[4]);
  EXPECT_FALSE(rt.queries.empty());
  const test::CommandResult described = test::run_dynscope("info " + rollout_trace);
  EXPECT_NE(described.output.find("source     rollout"), std::string::npos) << described.output;
  EXPECT_NE(run("trace --checkpoint " + ckpt + " --rollout " + rollout + " --frame 1 --out " +
                rollout_trace),
            0)
      << "frame 1 was observed, not predicted";
  EXPECT_NE(run("trace --checkpoint " + ckpt + " --rollout " + rollout + " --scene " + scene +
                " --out " + rollout_trace),
            0);
  // render draws the model's own level and lists: from the trace file, or traced on the fly.
  const fs::path frames = dir / "frames";
  ASSERT_EQ(run("render " + scene + " --trace " + trace + " --level 1 --pick 0 --no-video --out " +
                (frames / "a").string()),
            0);
  EXPECT_TRUE(fs::exists(frames / "a" / "frame_0004.png")) << "frames default to the trace's";
  EXPECT_NE(run("render " + scene + " --trace " + trace +
                " --level 1 --pick 0 --frames 5"
                " --no-video --out " +
                (frames / "b").string()),
            0)
      << "a trace holds one frame";
  ASSERT_EQ(run("render " + scene + " --checkpoint " + ckpt +
                " --frames 6 --level 1 --pick 1"
                " --no-video --out " +
                (frames / "c").string()),
            0);
  EXPECT_TRUE(fs::exists(frames / "c" / "frame_0006.png"));
  const ModelTrace traced = read_trace((frames / "c" / "trace.h5").string());
  EXPECT_EQ(traced.frame, 6);
  EXPECT_FALSE(traced.queries.empty()) << "the picked point's filter weights are traced";
  for (const TraceQuery& q : traced.queries) {
    if (q.level == 1) {
      EXPECT_EQ(q.query_index, 1) << q.conv;
    }
  }
  EXPECT_NE(run("render " + scene + " --checkpoint " + ckpt +
                " --level 1 --pick 100000"
                " --no-video --out " +
                (frames / "d").string()),
            0);
  EXPECT_EQ(info_kind(rollout), "rollout");
  EXPECT_EQ(info_kind(trace), "trace");
  EXPECT_EQ(info_kind(ckpt), "checkpoint");
  EXPECT_EQ(info_kind(scene), "scene");
  {
    // A checkpoint's description carries the normalisation statistics it was trained with.
    const test::CommandResult r = test::run_dynscope("info --json " + ckpt);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const nlohmann::json stats = nlohmann::json::parse(r.output).at("stats");
    for (const char* key : {"velocity_std", "target_std"}) {
      ASSERT_EQ(stats.at(key).size(), 3u) << key;
      for (const double s : stats.at(key)) {
        EXPECT_GT(s, 0.0) << key;
        EXPECT_NE(s, 1.0) << key << " is the untrained default";
      }
    }
  }
  {
    // A scene's description says how fast its points move against the model's radius.
    const test::CommandResult r = test::run_dynscope("info --json " + scene);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const nlohmann::json j = nlohmann::json::parse(r.output);
    const double fastest = j.at("motion").at("fastest_step");
    EXPECT_GT(fastest, 0.0) << "the probe moves";
    EXPECT_GT(j.at("motion").at("model_radius").get<double>(), 0.0);
    double largest = 0.0;
    for (const nlohmann::json& o : j.at("objects")) {
      largest = std::max(largest, o.at("max_step").get<double>());
    }
    EXPECT_EQ(largest, fastest);
    const int object = j.at("motion").at("fastest_object");
    EXPECT_EQ(j.at("objects").at(object).at("max_step").get<double>(), fastest);
  }
  // Bad input: one clear line, non-zero exit.
  EXPECT_NE(run("eval --checkpoint " + ckpt + " --data " + data + " --split training"), 0);
  EXPECT_NE(run("rollout --checkpoint " + (dir / "missing.pt").string() + " --scene " + scene +
                " --out " + rollout),
            0);
}

TEST(CliEndToEndTest, RecipeGeneratesItsDatasetsAndIsReproducible) {
  const fs::path dir =
      fs::temp_directory_path() / ("dynscope_cli_e2e_recipe_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string data = (dir / "data").string();
  const std::string recipe = (dir / "recipe.json").string();
  const nlohmann::json r = {
      {"description", "tiny"},
      {"datasets",
       {{{"out", data + "/drop"}, {"scenario", "drop"}, {"count", 10}, {"seed", 4}},
        {{"out", data + "/roll"},
         {"scenario", "roll"},
         {"count", 10},
         {"seed", 4},
         {"frame_rate_hz", 60}}}},
      {"data", {data + "/drop", data + "/roll"}},
      {"out", (dir / "a.pt").string()},
      {"log", (dir / "logs" / "train" / "a.csv").string()},
      {"model_config",
       {{"width", 8},
        {"levels", 2},
        {"bottleneck_blocks", 1},
        {"k", 6},
        {"k_relational", 6},
        {"c_mid", 4}}},
      {"max_steps", 2},
      {"val_scenes", 1},
      {"threads", 1},
      {"seed", 3},
      {"notes", {{"wall_time_s", 1.0}}}};
  { std::ofstream(recipe) << r.dump(2); }
  ASSERT_EQ(run("train --recipe " + recipe), 0);
  EXPECT_TRUE(fs::exists(fs::path(data) / "drop" / "manifest.json"));
  EXPECT_TRUE(fs::exists(fs::path(data) / "roll" / "manifest.json"));
  // The roll scenes are stored at 60 Hz instead of 30: 179 frames instead of 90.
  const nlohmann::json roll =
      nlohmann::json::parse(std::ifstream(fs::path(data) / "roll" / "manifest.json"));
  EXPECT_EQ(roll.at("parameters").at("frame_rate_hz"), 60.0);
  EXPECT_EQ(roll.at("parameters").at("num_frames"), 179);
  EXPECT_TRUE(fs::exists(dir / "logs" / "train" / "a.csv")) << "the log's directories are made";
  // The written recipe keeps datasets and notes; running it again gives the same weights.
  const std::string again = (dir / "b.pt").string();
  ASSERT_EQ(run("train --recipe " + (dir / "a.pt.recipe.json").string() + " --out " + again), 0);
  std::ifstream a(dir / "a.pt", std::ios::binary), b(again, std::ios::binary);
  const std::string bytes_a((std::istreambuf_iterator<char>(a)), std::istreambuf_iterator<char>());
  const std::string bytes_b((std::istreambuf_iterator<char>(b)), std::istreambuf_iterator<char>());
  EXPECT_EQ(info_kind(again), "checkpoint");
  const nlohmann::json written = nlohmann::json::parse(std::ifstream(dir / "a.pt.recipe.json"));
  EXPECT_EQ(written.at("datasets").size(), 2u);
  EXPECT_EQ(written.at("notes").at("wall_time_s"), 1.0);
  EXPECT_EQ(bytes_a.size(), bytes_b.size());
  fs::remove_all(dir);
}

TEST(CliEndToEndTest, MeshInputWithFaceReasoning) {
  const fs::path dir =
      fs::temp_directory_path() / ("dynscope_cli_e2e_mesh_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string data = (dir / "data").string();
  const std::string ckpt = (dir / "mesh.pt").string();
  ASSERT_EQ(run("generate --scenario movi-a --count 4 --seed 3 --out " + data), 0);
  ASSERT_EQ(run("train --data " + data +
                " --model pointconv --target acc --input mesh --faces on"
                " --out " +
                ckpt +
                " --max-steps 2 --width 8 --levels 2 --bottleneck-blocks 1"
                " --k 6 --c-mid 4 --threads 2"),
            0);
  const std::string scene = (fs::path(data) / "movi-a_0003.h5").string();
  const std::string rollout = (dir / "rollout.h5").string();
  ASSERT_EQ(run("rollout --checkpoint " + ckpt + " --scene " + scene + " --out " + rollout), 0);
  const Rollout r = read_rollout(rollout);
  EXPECT_GT(r.faces.rows(), 0) << "mesh input keeps the simplified faces";
  EXPECT_EQ(r.num_frames(), 24);
  const std::string trace = (dir / "trace.h5").string();
  ASSERT_EQ(run("trace --checkpoint " + ckpt + " --scene " + scene + " --frame 4 --out " + trace),
            0);
  EXPECT_TRUE(read_trace(trace).has_mesh);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace dynscope
