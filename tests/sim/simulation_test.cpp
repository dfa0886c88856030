// Tests of simulate(): recorded frames, free fall, the target-zone contact label, determinism.
#include "engine/sim/simulation.h"

#include <gtest/gtest.h>

#include "engine/core/error.h"

namespace dynscope {
namespace {

BodySpec box(int32_t id, Role role, const Vec3& position, const Vec3& half, double mass) {
  BodySpec b;
  b.object.id = id;
  b.object.name = "box_" + std::to_string(id);
  b.object.role = role;
  b.object.mass = mass;
  b.object.scale = half;
  b.parts.push_back(ShapePart{});
  b.pose.position = position;
  return b;
}

// A static zone pad on the floor and a target cube at `target_xy`, resting on the pad or the floor.
SimSetup pad_and_cube(const Vec3& target_position) {
  SimSetup s;
  s.scenario = "test";
  s.num_frames = 10;
  s.bodies.push_back(box(0, Role::kZone, Vec3(0, 0, 0.01), Vec3(0.2, 0.2, 0.01), 0.0));
  s.bodies.push_back(box(1, Role::kTarget, target_position, Vec3(0.05, 0.05, 0.05), 0.5));
  return s;
}

TEST(Simulate, TouchingPairIsLabelledInEveryFrame) {
  const Scene scene = simulate(pad_and_cube(Vec3(0, 0, 0.07)));
  ASSERT_EQ(scene.labels.count(kContactLabel), 1u);
  const std::vector<double>& label = scene.labels.at(kContactLabel);
  ASSERT_EQ(label.size(), 10u);
  for (double v : label) EXPECT_EQ(v, 1.0);
  EXPECT_TRUE(contact_outcome(scene));
}

TEST(Simulate, FarPairIsNeverLabelled) {
  const Scene scene = simulate(pad_and_cube(Vec3(1.0, 0, 0.05)));
  for (double v : scene.labels.at(kContactLabel)) EXPECT_EQ(v, 0.0);
  EXPECT_FALSE(contact_outcome(scene));
}

TEST(Simulate, FallingTargetIsLabelledFromImpactOn) {
  SimSetup s = pad_and_cube(Vec3(0, 0, 0.5));
  s.num_frames = 30;  // 1 s at 30 fps; the cube lands after about 0.29 s
  const Scene scene = simulate(s);
  const std::vector<double>& label = scene.labels.at(kContactLabel);
  EXPECT_EQ(label.front(), 0.0);
  EXPECT_EQ(label.back(), 1.0);
  const double impact = std::sqrt(2 * (0.5 - 0.07) / 9.81);
  const int first = static_cast<int>(std::find(label.begin(), label.end(), 1.0) - label.begin());
  EXPECT_NEAR(first * scene.dt_s, impact, 2 * scene.dt_s);
}

TEST(Simulate, RecordsFramesMeshesAndRates) {
  SimSetup s = pad_and_cube(Vec3(0, 0, 2.0));
  s.physics_rate_hz = 240;
  s.substeps_per_frame = 20;
  s.num_frames = 5;
  const Scene scene = simulate(s);
  EXPECT_NO_THROW(scene.validate());
  EXPECT_EQ(scene.num_frames(), 5);
  EXPECT_DOUBLE_EQ(scene.dt_s, 20.0 / 240.0);
  EXPECT_EQ(scene.scenario, "test");
  ASSERT_EQ(scene.objects.size(), 2u);
  EXPECT_EQ(scene.objects[1].mesh.num_vertices(), body_mesh(s.bodies[1].parts).num_vertices());
  EXPECT_TRUE(scene.objects[1].scale.isApprox(Vec3(0.05, 0.05, 0.05)));
  // Frame 0 is the initial state; the static pad never moves.
  EXPECT_TRUE(scene.trajectories[1].poses[0].position.isApprox(Vec3(0, 0, 2.0), 1e-6));
  for (const Pose& p : scene.trajectories[0].poses) EXPECT_NEAR(p.position.z(), 0.01, 1e-7);
}

TEST(Simulate, DroppedBodyFallsWithG) {
  SimSetup s;
  s.gravity = 9.81;
  s.num_frames = 6;
  s.bodies.push_back(box(0, Role::kOther, Vec3(0, 0, 3.0), Vec3(0.1, 0.1, 0.1), 1.0));
  const Scene scene = simulate(s);
  const double h = 1.0 / s.physics_rate_hz;
  for (int f = 1; f < 6; ++f) {
    const double t = f * scene.dt_s;
    // Semi-implicit Euler lags the exact parabola by g t h / 2.
    EXPECT_NEAR(scene.trajectories[0].poses[f].position.z(), 3.0 - 0.5 * 9.81 * t * t, 9.81 * t * h)
        << "frame " << f;
  }
  EXPECT_EQ(scene.labels.count(kContactLabel), 0u) << "no target/zone, no label";
}

TEST(Simulate, IsDeterministic) {
  SimSetup s = pad_and_cube(Vec3(0.1, 0.05, 0.4));
  s.bodies[1].angular_velocity = Vec3(1, 2, 3);
  s.bodies[1].linear_velocity = Vec3(0.5, 0, 0);
  s.num_frames = 40;
  const Scene a = simulate(s), b = simulate(s);
  for (int f = 0; f < a.num_frames(); ++f) {
    EXPECT_EQ(a.trajectories[1].poses[f].position, b.trajectories[1].poses[f].position);
    EXPECT_EQ(a.trajectories[1].poses[f].rotation.coeffs(),
              b.trajectories[1].poses[f].rotation.coeffs());
  }
  EXPECT_EQ(a.labels, b.labels);
}

TEST(Simulate, RejectsInconsistentSetups) {
  SimSetup s = pad_and_cube(Vec3(0, 0, 1));
  s.bodies[1].object.id = 0;
  EXPECT_THROW(simulate(s), ValueError);
  SimSetup t = pad_and_cube(Vec3(0, 0, 1));
  t.num_frames = 0;
  EXPECT_THROW(simulate(t), ValueError);
  EXPECT_THROW(simulate(SimSetup{}), ValueError);
}

}  // namespace
}  // namespace dynscope
