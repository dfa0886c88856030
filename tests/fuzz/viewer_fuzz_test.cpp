// The viewer on hostile inputs, headless (OSMesa, null platform) with the real model: every
// mutated scene, rollout, trace, view spec and checkpoint of the binary's fuzz suite, and meshes
// and foreign files opened from the Files panel, end either shown or in the error popup with the
// shown document kept, and the viewer goes on drawing. A crash, an abort or a hang here fails the
// test binary itself.
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "app/viewer/engine_model_services.h"
#include "app/viewer/null_platform.h"
#include "app/viewer/platform.h"
#include "app/viewer/viewer_app.h"
#include "render/context_factory.h"
#include "tests/fuzz/fuzz_util.h"
#include "tests/fuzz/mutations.h"

namespace dynscope::fuzz {
namespace {

namespace fs = std::filesystem;
using app::viewer::ViewerApp;
using app::viewer::ViewerState;

const std::string kSource = DYNSCOPE_SOURCE_DIR;
const std::string kScene = kSource + "/assets/scenes/movi-a_0000.h5";
const std::string kOtherScene = kSource + "/assets/scenes/collide_0000.h5";
const std::string kCheckpoint = kSource + "/assets/models/movi-a_pointconv_acc.pt";
constexpr double kSettleS = 60.0;  // a model load plus a trace take about a second

class ViewerFuzz : public ::testing::Test {
 protected:
  ViewerFuzz()
      : context_(render::create_context("osmesa", 480, 300)),
        platform_(480, 300),
        app_(*context_, platform_, &services_) {
    static std::atomic<int> counter{0};
    dir_ = fs::temp_directory_path() /
           ("dynscope-viewer-fuzz-" + std::to_string(getpid()) + "-" + std::to_string(counter++));
    fs::create_directories(dir_);
  }
  ~ViewerFuzz() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string file(const std::string& name) const { return (dir_ / name).string(); }

  // Draws frames until the action posted before has run and no job is left (at most kSettleS).
  void settle() {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(kSettleS);
    for (int i = 0; i < 2 || app_.state().busy(); ++i) {
      ASSERT_NO_THROW(app_.frame());
      ASSERT_LT(std::chrono::steady_clock::now(), end)
          << "a job ran for more than " << kSettleS << " s";
      if (app_.state().busy()) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }

  // Shows the good scene (must work at any point: the viewer is alive).
  void show_good_scene() {
    const int errors = app_.error_count();
    app_.request_open(kScene);
    settle();
    ASSERT_EQ(app_.error_count(), errors) << app_.last_error();
    ASSERT_TRUE(app_.state().has_scene());
    ASSERT_EQ(app_.state().document().path, kScene);
  }

  // Runs `action` in a frame as the panels would. It either succeeds or shows one error in the
  // popup, naming something, and leaves the scene that was shown before it.
  void expect_survives(const app::viewer::Action& action, const std::string& what) {
    const int errors = app_.error_count();
    const std::string shown = app_.state().has_scene() ? app_.state().document().path : "";
    app_.post(action);
    settle();
    if (HasFatalFailure()) {
      ADD_FAILURE() << "while: " << what;
      return;
    }
    ++runs_;
    if (app_.error_count() == errors) return;  // the mutation left a file the viewer can show
    ++failures_;
    if (std::getenv("DYNSCOPE_FUZZ_VERBOSE"))
      std::printf("%s -> %s\n", what.c_str(), app_.last_error().c_str());
    EXPECT_TRUE(app_.error_popup_open()) << what << ": error without the popup";
    EXPECT_FALSE(app_.last_error().empty()) << what;
    if (!shown.empty()) {
      ASSERT_TRUE(app_.state().has_scene()) << what << ": the shown scene was closed by a failure";
      EXPECT_EQ(app_.state().document().path, shown) << what;
    }
  }

  // Every mutation of `original`, copied to `input`, opened as the Files panel opens a file.
  void open_each(const std::string& original, const std::string& input,
                 const std::vector<Mutation>& mutations) {
    for (const Mutation& m : mutations) {
      fs::copy_file(original, input, fs::copy_options::overwrite_existing);
      m.apply(input);
      expect_survives([input](ViewerState& s) { s.open_file(input); }, m.name);
      if (HasFatalFailure()) return;
      // Back to a known document, so a failure has something to keep.
      show_good_scene();
      if (HasFatalFailure()) return;
    }
  }

  // The binary's own output of `args` + --out `path` (a rollout or a trace).
  void make_original(std::vector<std::string> args, const std::string& path) {
    args.push_back("--out");
    args.push_back(path);
    const RunResult r = run_binary(args, file("setup.log"), 120);
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }

  // The viewer still draws the scene after everything.
  void expect_alive() {
    show_good_scene();
    if (HasFatalFailure()) return;
    const render::Image image = app_.read_pixels();
    int distinct = 0;
    const uint8_t* first = image.rgba.data();
    for (size_t i = 0; i + 4 <= image.rgba.size(); i += 4 * 97) {
      if (!std::equal(first, first + 3, image.rgba.data() + i)) ++distinct;
    }
    EXPECT_GT(distinct, 0) << "the window is one flat colour";
  }

  app::viewer::EngineModelServices services_;
  std::unique_ptr<render::GlContext> context_;
  app::viewer::ImGuiSession session_;
  app::viewer::NullPlatform platform_;
  ViewerApp app_;
  fs::path dir_;
  int runs_ = 0, failures_ = 0;
};

TEST_F(ViewerFuzz, MutatedScenes) {
  show_good_scene();
  ASSERT_FALSE(HasFatalFailure());
  std::vector<Mutation> mutations = sample(h5_mutations(kScene, 1, 11), mutation_budget());
  const std::vector<Mutation> names = link_name_mutations(kScene);
  const std::vector<Mutation> some_names = sample(names, 8);
  mutations.insert(mutations.end(), some_names.begin(), some_names.end());
  open_each(kScene, file("scene.h5"), mutations);
  expect_alive();
  EXPECT_GE(runs_, 30);
  EXPECT_GE(failures_, 15);
}

TEST_F(ViewerFuzz, MutatedRollouts) {
  const std::string rollout = file("original_rollout.h5");
  make_original({"rollout", "--checkpoint", kCheckpoint, "--scene", kScene, "--frames", "6"},
                rollout);
  ASSERT_FALSE(HasFatalFailure());
  show_good_scene();
  ASSERT_FALSE(HasFatalFailure());
  open_each(rollout, file("rollout.h5"), sample(h5_mutations(rollout, 1, 12), mutation_budget()));
  expect_alive();
  EXPECT_GE(runs_, 25);
  EXPECT_GE(failures_, 10);
}

TEST_F(ViewerFuzz, MutatedTracesAndATraceOfAnotherScene) {
  const std::string trace = file("original_trace.h5");
  make_original(
      {"trace", "--checkpoint", kCheckpoint, "--scene", kScene, "--frame", "2", "--query", "0"},
      trace);
  ASSERT_FALSE(HasFatalFailure());
  show_good_scene();
  ASSERT_FALSE(HasFatalFailure());
  open_each(trace, file("trace.h5"), sample(h5_mutations(trace, 1, 13), mutation_budget()));
  // The unmutated trace on another scene: refused, naming the trace.
  app_.request_open(kOtherScene);
  settle();
  const int errors = app_.error_count();
  expect_survives([trace](ViewerState& s) { s.open_trace(trace); }, "trace of another scene");
  EXPECT_EQ(app_.error_count(), errors + 1);
  EXPECT_NE(app_.last_error().find("original_trace.h5"), std::string::npos) << app_.last_error();
  expect_alive();
  EXPECT_GE(runs_, 25);
}

TEST_F(ViewerFuzz, MutatedViewSpecs) {
  show_good_scene();
  ASSERT_FALSE(HasFatalFailure());
  const std::string original = file("original_view.json");
  app_.state().save_view(original);
  const std::string input = file("view.json");
  for (const Mutation& m : sample(json_mutations(original), mutation_budget())) {
    fs::copy_file(original, input, fs::copy_options::overwrite_existing);
    m.apply(input);
    expect_survives([input](ViewerState& s) { s.open_view(input); }, m.name);
    if (HasFatalFailure()) return;
  }
  expect_alive();
  EXPECT_GE(runs_, 25);
  EXPECT_GE(failures_, 5);
}

// A corrupted checkpoint fails in the background job that loads it: the popup shows the job's
// error and the scene stays.
TEST_F(ViewerFuzz, MutatedCheckpoints) {
  show_good_scene();
  ASSERT_FALSE(HasFatalFailure());
  // The unmutated checkpoint traces the frame (the job path the mutations go through).
  expect_survives(
      [](ViewerState& s) {
        s.set_frame(3);
        s.set_checkpoint(kCheckpoint);
      },
      "the bundled checkpoint");
  ASSERT_EQ(failures_, 0) << app_.last_error();
  ASSERT_NE(app_.state().shown_trace(), nullptr);
  const size_t size = static_cast<size_t>(fs::file_size(kCheckpoint));
  int m = 0;
  for (const Mutation& mutation : sample(byte_mutations(size, 6, 30, 6, 14), 16)) {
    // A new name each time: the model cache must not answer from an earlier file.
    const std::string input = file("model_" + std::to_string(m++) + ".pt");
    fs::copy_file(kCheckpoint, input);
    mutation.apply(input);
    expect_survives(
        [input](ViewerState& s) {
          s.set_frame(3);
          s.set_checkpoint(input);
        },
        mutation.name);
    if (HasFatalFailure()) return;
    app_.post([](ViewerState& s) { s.set_checkpoint(""); });
    settle();
  }
  expect_alive();
  EXPECT_GE(runs_, 17);
  EXPECT_GE(failures_, 8);
}

// What a user may pick in the Files panel that is no dynscope file at all: meshes (valid and
// mutated), a mesh header claiming 3.5e11 vertices, an empty file, random bytes, a PNG, a
// directory, a missing path.
TEST_F(ViewerFuzz, ForeignFiles) {
  show_good_scene();
  ASSERT_FALSE(HasFatalFailure());
  uint64_t seed = 30;
  for (const auto& [name, text] : mesh_files()) {
    const std::string original = file("original_" + name);
    write_bytes(original, text);
    std::vector<Mutation> mutations = {{"unchanged", [](const std::string&) {}}};
    const std::vector<Mutation> more =
        sample(name == "binary.ply" ? byte_mutations(text.size(), 4, 8, 1, seed)
                                    : mesh_mutations(text, seed),
               6);
    mutations.insert(mutations.end(), more.begin(), more.end());
    open_each(original, file(name), mutations);
    if (HasFatalFailure()) return;
    ++seed;
  }
  write_bytes(file("huge.off"), "OFF\n353535235358 1 0\n0 0 0\n3 0 0 0\n");
  write_bytes(file("empty.h5"), "");
  std::string noise(4096, '\0');
  Random rng(7);
  for (char& c : noise) c = static_cast<char>(rng.next());
  write_bytes(file("noise.h5"), noise);
  fs::create_directories(file("folder.h5"));
  for (const std::string& path :
       {file("huge.off"), file("empty.h5"), file("noise.h5"), file("folder.h5"), file("missing.h5"),
        kSource + "/assets/screenshots/viewer.png"}) {
    expect_survives([path](ViewerState& s) { s.open_file(path); }, path);
    if (HasFatalFailure()) return;
  }
  expect_alive();
  EXPECT_GE(failures_, 11);  // at least every foreign file and each unchanged mesh
}

}  // namespace
}  // namespace dynscope::fuzz
