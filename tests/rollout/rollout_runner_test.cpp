// Rollout loop: an oracle reproduces ground truth and poses; the baseline; bad options.
#include "engine/rollout/rollout_runner.h"

#include <gtest/gtest.h>

#include "engine/core/error.h"
#include "engine/rollout/metrics.h"
#include "tests/rollout/rollout_test_util.h"

namespace dynscope {
namespace {

TEST(RolloutRunnerTest, OracleRolloutReproducesTruthAndPoses) {
  const Scene scene = testing::make_moving_boxes(10, 0.25);
  const ModelPoints points = build_model_points(scene, SamplingOptions{InputMode::kPoints, 0.05});
  RolloutOptions options;
  options.observed_frames = 3;
  const Rollout r = run_rollout(scene, points, testing::oracle_predictor(scene, points), options);
  ASSERT_EQ(r.num_frames(), 10);
  EXPECT_NO_THROW(r.validate());
  for (int f = 0; f < 10; ++f) {
    EXPECT_LT(r.point_error[static_cast<size_t>(f)], 1e-9) << "frame " << f;
    const Pose& truth = scene.trajectories[0].poses[static_cast<size_t>(f)];
    EXPECT_LT((r.poses[static_cast<size_t>(f)][0].position - truth.position).norm(), 1e-9);
    EXPECT_LT(r.poses[static_cast<size_t>(f)][0].rotation.angularDistance(truth.rotation), 1e-7);
  }
  ASSERT_TRUE(r.has_contact());
  // The target approaches the zone at x = 3: distance shrinks frame by frame.
  EXPECT_LT(r.contact_distance_truth.back(), r.contact_distance_truth.front());
  for (size_t f = 0; f < r.contact_distance_truth.size(); ++f) {
    EXPECT_NEAR(r.contact_distance_truth[f], r.contact_distance_predicted[f], 1e-9);
  }
}

TEST(RolloutRunnerTest, RecordsThePointsOfStaticBodies) {
  Scene scene = testing::make_moving_boxes(6, 0.25);
  scene.objects[1].mass = 0.0;  // the zone pad: static
  const ModelPoints points = build_model_points(scene, SamplingOptions{InputMode::kPoints, 0.05});
  const Rollout r =
      run_rollout(scene, points, testing::oracle_predictor(scene, points), RolloutOptions{});
  ASSERT_EQ(r.static_points.size(), static_cast<size_t>(points.cloud.size()));
  for (size_t i = 0; i < r.static_points.size(); ++i) {
    EXPECT_EQ(r.static_points[i], r.object_ids[i] == 2 ? 1 : 0) << i;
  }
}

TEST(RolloutRunnerTest, ConstantVelocityBaselineIsExactForUniformMotionWithoutGravity) {
  Scene scene = testing::make_moving_boxes(8, 0.3);
  for (Pose& p : scene.trajectories[0].poses) p.rotation = Quat::Identity();
  const ModelPoints points = build_model_points(scene, SamplingOptions{InputMode::kPoints, 0.1});
  RolloutOptions options;
  const Rollout r =
      run_rollout(scene, points, constant_velocity_predictor(0.0, scene.dt_s), options);
  EXPECT_LT(r.point_error.back(), 1e-9);
  // With gravity the baseline drops by g·dt² per frame and step: error grows.
  const Rollout g =
      run_rollout(scene, points, constant_velocity_predictor(9.81, scene.dt_s), options);
  EXPECT_GT(g.point_error.back(), g.point_error[3]);
  EXPECT_GT(g.point_error[3], 0.0);
}

TEST(RolloutRunnerTest, RejectsTooFewObservedFrames) {
  const Scene scene = testing::make_moving_boxes(6);
  const ModelPoints points = build_model_points(scene, SamplingOptions{InputMode::kPoints, 0.1});
  RolloutOptions options;
  options.observed_frames = 2;
  try {
    run_rollout(scene, points, constant_velocity_predictor(0, 0.1), options);
    FAIL() << "expected ValueError";
  } catch (const ValueError& e) {
    EXPECT_EQ(e.name(), "observed");
  }
  options.observed_frames = 3;
  options.frames = 7;
  EXPECT_THROW(run_rollout(scene, points, constant_velocity_predictor(0, 0.1), options),
               ValueError);
}

TEST(RolloutRunnerTest, PredictorWithWrongRowsIsAClearError) {
  const Scene scene = testing::make_moving_boxes(6);
  const ModelPoints points = build_model_points(scene, SamplingOptions{InputMode::kPoints, 0.1});
  const StepPredictor bad = [](const PointState&) { return Points(Points::Zero(2, 3)); };
  EXPECT_THROW(run_rollout(scene, points, bad, RolloutOptions{}), ValueError);
}

TEST(ModelPointsTest, MeshInputUsesSimplifiedVerticesAndFaces) {
  const Scene scene = testing::make_moving_boxes(3);
  const ModelPoints points = build_model_points(scene, SamplingOptions{InputMode::kMesh, 0.05});
  EXPECT_EQ(points.size(), 16);  // two boxes, 8 corners each
  EXPECT_EQ(points.faces.rows(), 24);
  EXPECT_EQ(points.faces.maxCoeff(), 15);
  EXPECT_NEAR(default_sampling_voxel("movi-a"), 0.2, 0);
  EXPECT_EQ(default_scale_preset("drop"), "physion");
}

}  // namespace
}  // namespace dynscope
