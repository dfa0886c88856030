// RigidProjector: recovers object poses from noisy points, leaves non-rigid points, floor clamp.
#include "engine/rollout/pose_fitting.h"

#include <gtest/gtest.h>

#include "engine/core/error.h"
#include "engine/core/rng.h"
#include "engine/rollout/model_points.h"
#include "tests/rollout/rollout_test_util.h"

namespace dynscope {
namespace {

TEST(RigidProjectorTest, NoisyTruePointsProjectBackOntoTheTruePose) {
  const Scene scene = testing::make_moving_boxes(6);
  SamplingOptions so;
  so.voxel = 0.05;
  const ModelPoints points = build_model_points(scene, so);
  const RigidProjector projector(points.cloud, {1, 1});
  const Points truth = points.positions(scene, 5);
  Rng rng(3);
  Points noisy = truth;
  for (Eigen::Index i = 0; i < noisy.size(); ++i) noisy.data()[i] += rng.normal(0.0, 0.002);
  std::vector<Pose> poses;
  const Points projected = projector.project(noisy, &poses);
  // Zero-mean noise averages out over the object's points: the fit is far closer than the noise.
  EXPECT_LT((projected - truth).rowwise().norm().maxCoeff(), 0.002);
  ASSERT_EQ(poses.size(), 2u);
  const Pose& expected = scene.trajectories[0].poses[5];
  EXPECT_LT((poses[0].position - expected.position).norm(), 1e-3);
  EXPECT_LT(poses[0].rotation.angularDistance(expected.rotation), 5e-3);
  // Exact true points give the exact pose.
  const Points exact = projector.project(truth, &poses);
  EXPECT_LT((exact - truth).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(RigidProjectorTest, NonRigidObjectsKeepTheirPredictedPoints) {
  const Scene scene = testing::make_moving_boxes(3);
  SamplingOptions so;
  so.voxel = 0.1;
  const ModelPoints points = build_model_points(scene, so);
  const RigidProjector projector(points.cloud, {1, 0});
  Rng rng(1);
  Points noisy = points.positions(scene, 2);
  for (Eigen::Index i = 0; i < noisy.size(); ++i) noisy.data()[i] += rng.normal(0.0, 0.01);
  std::vector<Pose> poses;
  const Points projected = projector.project(noisy, &poses);
  for (Eigen::Index i = 0; i < noisy.rows(); ++i) {
    if (points.cloud.object[static_cast<size_t>(i)] == 1) {
      EXPECT_EQ(projected.row(i), noisy.row(i));
    }
  }
  EXPECT_TRUE(poses[1].position.isZero());
}

TEST(RigidProjectorTest, FloorClampLiftsSunkenObjects) {
  const Scene scene = testing::make_moving_boxes(2);
  SamplingOptions so;
  so.voxel = 0.1;
  const ModelPoints points = build_model_points(scene, so);
  const RigidProjector projector(points.cloud, {1, 1});
  Points p = points.positions(scene, 0);
  p.col(2).array() -= 1.0;  // both boxes below the floor
  std::vector<Pose> poses;
  p = projector.project(p, &poses);
  projector.clamp_to_floor(p, poses);
  EXPECT_NEAR(p.col(2).minCoeff(), 0.0, 1e-12);
  for (Eigen::Index i = 0; i < p.rows(); ++i) EXPECT_GE(p(i, 2), -1e-12);
}

TEST(RigidProjectorTest, WrongRowCountNamesTheField) {
  const Scene scene = testing::make_moving_boxes(2);
  const ModelPoints points = build_model_points(scene, SamplingOptions{InputMode::kPoints, 0.1});
  const RigidProjector projector(points.cloud, {1, 1});
  try {
    projector.project(Points::Zero(3, 3));
    FAIL() << "expected ValueError";
  } catch (const ValueError& e) {
    EXPECT_EQ(e.name(), "predicted");
  }
}

}  // namespace
}  // namespace dynscope
