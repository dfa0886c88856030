// Fuzz suite: structured mutations of every file kind the commands read (scenes, rollouts, traces,
// checkpoints, recipes, view specs, meshes), each run through the built binary. Every run must
// exit 0 or fail with one "dynscope: error:" line, never end by a signal or a timeout, stay under
// 2 GB, and leave the outputs of an earlier run unchanged when it fails.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tests/fuzz/fuzz_util.h"
#include "tests/fuzz/mutations.h"

namespace dynscope::fuzz {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

const std::string kSource = DYNSCOPE_SOURCE_DIR;
const std::string kScene = kSource + "/assets/scenes/movi-a_0000.h5";
const std::string kCheckpoint = kSource + "/assets/models/movi-a_pointconv_acc.pt";
constexpr double kTimeoutS = 20.0;
constexpr long kMaxRssKb = 2L * 1024 * 1024;

// A scratch directory for one test, removed at the end.
class Scratch {
 public:
  Scratch() {
    static std::atomic<int> counter{0};
    dir_ = fs::temp_directory_path() /
           ("dynscope-fuzz-" + std::to_string(getpid()) + "-" + std::to_string(counter++));
    fs::create_directories(dir_);
  }
  ~Scratch() {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string file(const std::string& name) const { return (dir_ / name).string(); }

 private:
  fs::path dir_;
};

// Outputs a command may replace; they hold sentinel bytes that must survive a failed run.
struct Outputs {
  std::vector<std::string> files;
  void plant() const {
    for (const std::string& f : files) {
      fs::create_directories(fs::path(f).parent_path());
      write_bytes(f, "sentinel of an earlier run: " + f);
    }
  }
  void expect_unchanged(const std::string& what) const {
    for (const std::string& f : files) {
      EXPECT_EQ(read_bytes(f), "sentinel of an earlier run: " + f)
          << what << ": a failed run changed " << f;
    }
  }
};

// Runs `args` and checks the run's ending; `what` names the mutation in failure messages.
void expect_clean_run(const std::vector<std::string>& args, const Outputs& outputs,
                      const std::string& log, const std::string& what) {
  outputs.plant();
  const RunResult r = run_binary(args, log, kTimeoutS);
  std::string command;
  for (const std::string& a : args) command += " " + a;
  const std::string context = what + "\n  dynscope" + command + "\n" + r.output;
  ASSERT_FALSE(r.timed_out) << "timed out after " << kTimeoutS << " s: " << context;
  ASSERT_EQ(r.signal, 0) << "killed by signal " << r.signal << " (" << strsignal(r.signal)
                         << "): " << context;
  EXPECT_LT(r.max_rss_kb, kMaxRssKb) << "peak memory " << r.max_rss_kb << " kB: " << context;
  if (r.exit_code == 0) return;
  // The error is the last line: "dynscope: error: ..." on one line.
  std::string text = r.output.substr(0, r.output.find_last_not_of("\n") + 1);
  const std::string last = text.substr(text.find_last_of('\n') + 1);
  EXPECT_EQ(last.rfind("dynscope: error: ", 0), 0u) << "no one-line error: " << context;
  outputs.expect_unchanged(context);
}

// Runs every mutation of `original` (copied to `input` first) through each of `commands`
// (argument lists where "{}" stands for the input); command k runs for every `stride[k]`-th
// mutation only, so slow commands see a sample.
struct Command {
  std::vector<std::string> args;
  Outputs outputs;
  size_t stride = 1;
};

int fuzz_file(const std::string& original, const std::string& input,
              const std::vector<Mutation>& all_mutations, const std::vector<Command>& commands,
              const std::string& log, size_t budget = mutation_budget()) {
  const std::vector<Mutation> mutations = sample(all_mutations, budget);
  int runs = 0;
  for (size_t m = 0; m < mutations.size(); ++m) {
    fs::copy_file(original, input, fs::copy_options::overwrite_existing);
    mutations[m].apply(input);
    for (const Command& c : commands) {
      if (m % c.stride != 0) continue;
      std::vector<std::string> args = c.args;
      for (std::string& a : args) {
        if (a == "{}") a = input;
      }
      expect_clean_run(args, c.outputs, log, mutations[m].name);
      ++runs;
      if (::testing::Test::HasFatalFailure()) return runs;
    }
  }
  return runs;
}

// Each test in a scratch directory (ctest runs every test in its own process).
class FileFuzz : public ::testing::Test {
 protected:
  // Writes the binary's own output of `args` (a rollout or a trace of the bundled scene) to
  // `path`, the original that the test then mutates.
  void make_original(std::vector<std::string> args, const std::string& path) {
    args.push_back("--out");
    args.push_back(path);
    const RunResult r = run_binary(args, scratch_.file("setup.log"), 120);
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }

  Scratch scratch_;
};

TEST_F(FileFuzz, Scenes) {
  const std::string input = scratch_.file("scene.h5");
  const std::string out = scratch_.file("frames");
  const int runs = fuzz_file(
      kScene, input, h5_mutations(kScene, 1, 11),
      {{{"info", "{}"}, {}, 1},
       {{"render", "{}", "--out", out, "--frames", "0:2", "--no-video", "--size", "64x48"},
        {{out + "/frame_0000.png", out + "/view.json", out + "/contact_sheet.png"}},
        5}},
      scratch_.file("log"));
  EXPECT_GE(runs, 30);
}

// Corrupted link names in /frames once made HDF5 crash or double-free while listing the frames.
TEST_F(FileFuzz, ScenesWithCorruptFrameLinkNames) {
  const std::vector<Mutation> names = link_name_mutations(kScene);
  ASSERT_GE(names.size(), 16u) << "the frame link names were not found in the file";
  const int runs = fuzz_file(kScene, scratch_.file("scene.h5"), names, {{{"info", "{}"}, {}, 1}},
                             scratch_.file("log"), names.size());
  EXPECT_EQ(runs, static_cast<int>(names.size()));
}

TEST_F(FileFuzz, Rollouts) {
  const std::string rollout = scratch_.file("original.h5");
  make_original({"rollout", "--checkpoint", kCheckpoint, "--scene", kScene, "--frames", "6"},
                rollout);
  ASSERT_FALSE(HasFatalFailure());
  const std::string input = scratch_.file("rollout.h5");
  const std::string out = scratch_.file("frames");
  const int runs = fuzz_file(
      rollout, input, h5_mutations(rollout, 1, 12),
      {{{"info", "{}"}, {}, 1},
       {{"render", "{}", "--out", out, "--frames", "0:2", "--no-video", "--size", "64x48"},
        {{out + "/frame_0000.png", out + "/view.json"}},
        4}},
      scratch_.file("log"));
  EXPECT_GE(runs, 28);
}

TEST_F(FileFuzz, Traces) {
  const std::string trace = scratch_.file("original.h5");
  make_original(
      {"trace", "--checkpoint", kCheckpoint, "--scene", kScene, "--frame", "2", "--query", "0"},
      trace);
  ASSERT_FALSE(HasFatalFailure());
  const std::string input = scratch_.file("trace.h5");
  const std::string out = scratch_.file("frames");
  const int runs = fuzz_file(
      trace, input, h5_mutations(trace, 1, 13),
      {{{"info", "{}"}, {}, 1},
       {{"render", kScene, "--trace", "{}", "--out", out, "--no-video", "--size", "64x48"},
        {{out + "/frame_0002.png", out + "/view.json"}},
        4}},
      scratch_.file("log"));
  EXPECT_GE(runs, 28);
}

TEST_F(FileFuzz, Checkpoints) {
  const std::string input = scratch_.file("model.pt");
  const std::string out = scratch_.file("rollout.h5");
  const size_t size = static_cast<size_t>(fs::file_size(kCheckpoint));
  const int runs = fuzz_file(
      kCheckpoint, input, byte_mutations(size, 8, 48, 8, 14),
      {{{"info", "{}"}, {}, 1},
       {{"rollout", "--checkpoint", "{}", "--scene", kScene, "--out", out, "--frames", "5"},
        {{out}},
        6}},
      scratch_.file("log"));
  EXPECT_GE(runs, 28);
}

TEST_F(FileFuzz, Recipes) {
  // A recipe is read next to its checkpoint (sampling) and by train --recipe.
  const std::string checkpoint = scratch_.file("model.pt");
  fs::copy_file(kCheckpoint, checkpoint);
  const std::string original = kCheckpoint + ".recipe.json";
  const std::string out = scratch_.file("trace.h5");
  const int runs = fuzz_file(
      original, checkpoint + ".recipe.json", json_mutations(original),
      {{{"train", "--recipe", "{}", "--data", scratch_.file("no-data"), "--out",
         scratch_.file("train.pt")},
        {},
        1},
       {{"trace", "--checkpoint", checkpoint, "--scene", kScene, "--out", out}, {{out}}, 3}},
      scratch_.file("log"));
  EXPECT_GE(runs, 28);
}

TEST_F(FileFuzz, ViewSpecs) {
  const std::string out = scratch_.file("frames");
  const std::string view = scratch_.file("view.json");
  {
    // The view the renderer itself writes, as the viewer would save it.
    const RunResult r = run_binary({"render", kScene, "--out", scratch_.file("first"), "--frames",
                                    "0", "--no-video", "--size", "64x48"},
                                   scratch_.file("log"), kTimeoutS);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    fs::copy_file(scratch_.file("first/view.json"), scratch_.file("original.json"));
  }
  const int runs = fuzz_file(
      scratch_.file("original.json"), view, json_mutations(scratch_.file("original.json")),
      {{{"render", kScene, "--view", "{}", "--out", out, "--frames", "0", "--no-video"},
        {{out + "/frame_0000.png", out + "/view.json"}},
        1}},
      scratch_.file("log"));
  EXPECT_GE(runs, 28);
}

TEST_F(FileFuzz, Meshes) {
  int runs = 0;
  uint64_t seed = 20;
  for (const auto& [name, text] : mesh_files()) {
    const std::string original = scratch_.file("original_" + name);
    write_bytes(original, text);
    // Binary files are mutated byte-wise only.
    std::vector<Mutation> mutations = name == "binary.ply"
                                          ? byte_mutations(text.size(), 8, 24, 2, seed)
                                          : mesh_mutations(text, seed);
    runs += fuzz_file(original, scratch_.file(name), mutations, {{{"info", "{}"}, {}, 1}},
                      scratch_.file("log"), std::max<size_t>(4, mutation_budget() * 3 / 7));
    ++seed;
  }
  EXPECT_GE(runs, 60);
}

}  // namespace
}  // namespace dynscope::fuzz
