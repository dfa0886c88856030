// Regression guards for the shipped models: the default model loads, and its rollout of each
// bundled movi-a sample ends closer to the truth than the constant-velocity-plus-gravity
// baseline; the Physion-like model passes the probe's momentum on in the bundled collide sample
// whose target reaches the zone.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "engine/io/scene_file.h"
#include "engine/model/torch_runtime.h"
#include "engine/rollout/evaluation.h"
#include "engine/rollout/model_predictor.h"
#include "engine/train/train_options.h"

namespace dynscope {
namespace {

const std::string kSource = DYNSCOPE_SOURCE_DIR;
const std::string kDefaultCheckpoint = kSource + "/assets/models/movi-a_pointconv_acc.pt";
const std::string kPhysionCheckpoint = kSource + "/assets/models/physion_pointconv_acc.pt";

TEST(DefaultCheckpointTest, LoadsAndDescribesItself) {
  ASSERT_TRUE(std::filesystem::exists(kDefaultCheckpoint)) << kDefaultCheckpoint;
  const LoadedModel model = load_model(kDefaultCheckpoint);
  EXPECT_EQ(model.config.kind, ModelKind::kPointConv);
  EXPECT_EQ(model.config.target, TargetMode::kAcceleration);
  EXPECT_EQ(model.config.input, InputMode::kPoints);
  const SamplingOptions sampling = checkpoint_sampling(kDefaultCheckpoint, model.config);
  EXPECT_GT(sampling.voxel, 0.0) << "the recipe next to the checkpoint gives its sampling";
}

TEST(DefaultCheckpointTest, BeatsConstantVelocityBaselineOnBundledSamples) {
  set_torch_threads(2);
  const LoadedModel model = load_model(kDefaultCheckpoint);
  const SamplingOptions sampling = checkpoint_sampling(kDefaultCheckpoint, model.config);
  for (const char* name : {"movi-a_0000.h5", "movi-a_0001.h5"}) {
    SCOPED_TRACE(name);
    const Scene scene = read_scene(kSource + "/assets/scenes/" + name);
    const ModelPoints points = build_model_points(scene, sampling);
    RolloutOptions options;
    options.observed_frames = 3;
    const Rollout predicted = run_rollout(scene, points, model.predict, options);
    const Rollout baseline = run_baseline_rollout(scene, points, options);
    ASSERT_EQ(predicted.num_frames(), scene.num_frames());
    EXPECT_LT(predicted.point_error.back(), baseline.point_error.back());
  }
}

// The failure the squared-error loss fixed: the probe's momentum is passed on, so the struck
// target reaches the zone as in the truth (a model trained with Huber delta = 1 target std never
// moved it). The negative sample collide_0001 is not asserted: the shipped model still pushes
// its target to 0.02 of the zone, where the truth stays 0.22 away (README, Results).
TEST(DefaultCheckpointTest, PhysionModelPassesTheProbesMomentumOnInCollide) {
  set_torch_threads(2);
  const LoadedModel model = load_model(kPhysionCheckpoint);
  EvalOptions options;
  options.sampling = checkpoint_sampling(kPhysionCheckpoint, model.config);
  options.baseline = false;
  const std::string file = "collide_0000.h5";
  const DatasetItem item{kSource + "/assets/scenes/" + file, file, 1};
  const SceneEvaluation e = evaluate_scene(item, model.predict, options, nullptr, nullptr);
  ASSERT_TRUE(e.has_contact);
  EXPECT_EQ(e.label, 1) << "assets/scenes/collide_manifest.json labels it a contact";
  EXPECT_TRUE(e.truth_contact);
  EXPECT_TRUE(e.model_contact) << "closest predicted target-zone distance " << e.model_min_distance
                               << ", threshold 0.05";
}

}  // namespace
}  // namespace dynscope
