// The viewer with the real model (EngineModelServices, LibTorch): the Explain panel's job on a
// rollout of the bundled Physion-like checkpoint gives what `dynscope explain` computes.
#include <gtest/gtest.h>

#include <chrono>
#include <string>

#include "app/cli_util.h"
#include "app/viewer/engine_model_services.h"
#include "engine/io/scene_file.h"
#include "engine/rollout/explain.h"
#include "engine/rollout/explain_report.h"
#include "viewer_test_util.h"

namespace dynscope::app::viewer {
namespace {

const std::string kCheckpoint =
    std::string(DYNSCOPE_SOURCE_DIR) + "/assets/models/physion_pointconv_acc.pt";

TEST(ViewerEngine, TheExplainJobIsTheEnginesExplanationOfTheDivergence) {
  const Scene scene = read_scene(testing::collide_scene());
  RolloutOptions options;
  options.frames = 20;
  const Rollout rollout = rollout_checkpoint(kCheckpoint, scene, testing::collide_scene(), options);

  // What `dynscope explain` computes for the same rollout.
  const RolloutExplainer explainer(kCheckpoint);
  const Divergence divergence = find_divergence(rollout, explainer.config());
  ASSERT_TRUE(divergence.found());
  const Explanation want = explainer.explain(
      rollout, resolve_selection(rollout, divergence, -1, -1, -1, ExplainTarget::kError));

  EngineModelServices services;
  testing::HeadlessViewer v(&services);
  ViewerState& state = v.app.state();
  state.open_scene(testing::collide_scene());
  state.set_rollout(rollout, "rollout", &scene);
  state.set_checkpoint(kCheckpoint);
  state.start_explain(-1, -1, -1, ExplainTarget::kError);
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while ((state.busy() || !state.explanation()) && std::chrono::steady_clock::now() < end) {
    v.app.frame();
  }
  ASSERT_NE(state.explanation(), nullptr) << v.app.last_error();
  const Explanation& got = state.explanation()->explanation;
  EXPECT_EQ(state.explanation()->divergence.frame, divergence.frame);
  EXPECT_EQ(got.frame, want.frame);
  EXPECT_EQ(got.object, want.object);
  ASSERT_EQ(got.contributors.size(), want.contributors.size());
  for (size_t i = 0; i < got.contributors.size(); ++i) {
    EXPECT_EQ(got.contributors[i].list, want.contributors[i].list);
    EXPECT_EQ(got.contributors[i].object, want.contributors[i].object);
    EXPECT_NEAR(got.contributors[i].share, want.contributors[i].share, 1e-9);
  }
  // One model load serves the trace and the explanation jobs.
  EXPECT_EQ(state.model_cache()->loads(), 1);
  v.app.frame();
  EXPECT_EQ(v.app.error_count(), 0) << v.app.last_error();
}

}  // namespace
}  // namespace dynscope::app::viewer
