// Golden screenshots of the whole viewer UI (960x600, OSMesa, null platform) compared within a
// small per-pixel tolerance; DYNSCOPE_UPDATE_GOLDEN=1 (tests/app/update_goldens.sh) rewrites them.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>

#include "engine/io/rollout_file.h"
#include "engine/io/scene_file.h"
#include "engine/rollout/model_points.h"
#include "engine/rollout/rollout_runner.h"
#include "fake_model.h"
#include "render/image.h"
#include "render/png_io.h"
#include "viewer_test_util.h"

namespace dynscope::app::viewer {
namespace {

namespace fs = std::filesystem;

constexpr int kTolerance = 8;           // max channel difference of a matching pixel
constexpr double kMinFraction = 0.995;  // share of pixels that must match

void expect_matches_golden(const render::Image& actual, const std::string& name) {
  const fs::path golden = fs::path(DYNSCOPE_SOURCE_DIR) / "tests/app/golden" / (name + ".png");
  const char* update = std::getenv("DYNSCOPE_UPDATE_GOLDEN");
  if (update && std::string(update) == "1") {
    render::write_png(golden.string(), actual);
    std::printf("updated %s\n", golden.c_str());
    return;
  }
  ASSERT_TRUE(fs::exists(golden)) << golden << " is missing; run tests/app/update_goldens.sh";
  const render::Image expected = render::read_png(golden.string());
  const render::ImageComparison c = render::compare_images(actual, expected, kTolerance);
  if (c.fraction_within < kMinFraction) {
    const fs::path dir = DYNSCOPE_VIEWER_ARTIFACT_DIR;
    fs::create_directories(dir);
    const fs::path actual_path = dir / (name + "_actual.png");
    const fs::path diff_path = dir / (name + "_diff.png");
    render::write_png(actual_path.string(), actual);
    render::write_png(diff_path.string(), c.diff);
    ADD_FAILURE() << name << ": only " << 100.0 * c.fraction_within << "% of pixels within "
                  << kTolerance << " (max difference " << c.max_difference
                  << ")\n  golden: " << golden.string() << "\n  actual: " << actual_path.string()
                  << "\n  diff:   " << diff_path.string();
  }
}

// A few frames so ImGui settles its layout (auto-sized columns, opened sections).
render::Image settle(testing::HeadlessViewer& v) {
  for (int i = 0; i < 3; ++i) v.app.frame();
  return v.app.read_pixels();
}

TEST(ViewerGolden, NeighbourhoodInspector) {
  testing::HeadlessViewer v;
  v.app.state().open_scene(testing::collide_scene());
  v.app.state().set_frame(9);
  v.app.state().select_point(17);
  expect_matches_golden(settle(v), "viewer_neighbourhood");
}

TEST(ViewerGolden, LevelBrowser) {
  testing::HeadlessViewer v;
  v.app.state().open_scene(testing::collide_scene());
  v.app.state().set_frame(9);
  v.app.state().set_level(1);
  v.app.state().layers().voxels = true;
  v.app.state().show_panel(Panel::kLevels);
  v.app.state().show_panel(Panel::kObjects);
  expect_matches_golden(settle(v), "viewer_levels");
}

TEST(ViewerGolden, RolloutSideBySide) {
  // A constant-velocity rollout (torch-free) of the collide scene, written and reopened.
  const Scene scene = read_scene(testing::collide_scene());
  SamplingOptions sampling;
  sampling.voxel = 0.1;
  RolloutOptions options;
  options.floor_clamp = true;
  Rollout r = run_rollout(scene, build_model_points(scene, sampling),
                          constant_velocity_predictor(9.81, scene.dt_s), options);
  r.scene_path = testing::collide_scene();
  r.sampling_voxel = sampling.voxel;
  const fs::path file = fs::temp_directory_path() / "dynscope_viewer_golden_rollout.h5";
  write_rollout(r, file.string());
  testing::HeadlessViewer v;
  v.app.state().open_rollout(file.string());
  v.app.state().set_rollout_mode(RolloutMode::kSideBySide);
  v.app.state().set_frame(40);
  v.app.state().show_panel(Panel::kContacts);
  expect_matches_golden(settle(v), "viewer_rollout");
}

TEST(ViewerGolden, ExplainPanel) {
  // The fake model's explanation of the constant-velocity collide rollout's divergence.
  testing::FakeModel model;
  testing::HeadlessViewer v(&model);
  ViewerState& state = v.app.state();
  state.open_scene(testing::collide_scene());
  const Scene scene = state.document().scene;
  state.set_rollout(testing::cv_rollout(scene, testing::collide_scene()), "rollout", &scene);
  state.set_checkpoint("fake.pt");
  state.start_explain(-1, -1, -1, ExplainTarget::kError);
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while ((state.busy() || !state.explanation()) && std::chrono::steady_clock::now() < end) {
    v.app.frame();
  }
  ASSERT_NE(state.explanation(), nullptr) << v.app.last_error();
  state.show_panel(Panel::kRollout, false);
  state.show_panel(Panel::kModel, false);
  expect_matches_golden(settle(v), "viewer_explain");
}

}  // namespace
}  // namespace dynscope::app::viewer
