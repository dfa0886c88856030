// Tests of the Bullet world wrapper: free fall, contacts, overlap tests, joints, bad input.
#include "engine/sim/bullet_world.h"

#include <gtest/gtest.h>

#include "engine/core/error.h"

namespace dynscope {
namespace {

BodySpec ball(int32_t id, const Vec3& position, double radius = 0.1, double mass = 1.0) {
  BodySpec b;
  b.object.id = id;
  b.object.name = "ball_" + std::to_string(id);
  b.object.mass = mass;
  b.object.scale = Vec3::Constant(radius);
  ShapePart p;
  p.kind = ShapeKind::kSphere;
  b.parts.push_back(p);
  b.pose.position = position;
  return b;
}

BodySpec box(int32_t id, const Vec3& position, const Vec3& half, double mass = 1.0) {
  BodySpec b;
  b.object.id = id;
  b.object.name = "box_" + std::to_string(id);
  b.object.mass = mass;
  b.object.scale = half;
  b.parts.push_back(ShapePart{});
  b.pose.position = position;
  return b;
}

TEST(BulletWorld, FreeFallFollowsSemiImplicitEuler) {
  WorldOptions options;
  options.gravity = 9.81;
  options.physics_dt_s = 1.0 / 240.0;
  BulletWorld world(options);
  const int i = world.add_body(ball(0, Vec3(0, 0, 5)));
  const double h = options.physics_dt_s;
  for (int n = 1; n <= 48; ++n) {
    world.step();
    // Bullet integrates v += g h, then x += v h: x_n = x_0 - g h^2 n (n + 1) / 2.
    EXPECT_NEAR(world.pose(i).position.z(), 5.0 - 9.81 * h * h * n * (n + 1) / 2, 1e-5);
    EXPECT_NEAR(world.linear_velocity(i).z(), -9.81 * h * n, 1e-4);
  }
  EXPECT_NEAR(world.pose(i).position.x(), 0.0, 1e-9);
}

TEST(BulletWorld, ContactBetweenTouchingBodiesOnly) {
  BulletWorld world(WorldOptions{});
  const int pad = world.add_body(box(0, Vec3(0, 0, 0.01), Vec3(0.2, 0.2, 0.01), 0.0));
  const int on = world.add_body(box(1, Vec3(0, 0, 0.07), Vec3(0.05, 0.05, 0.05)));
  const int far = world.add_body(box(2, Vec3(1, 0, 0.05), Vec3(0.05, 0.05, 0.05)));
  world.detect_contacts();
  EXPECT_TRUE(world.in_contact(pad, on, 1e-3));
  EXPECT_TRUE(world.in_contact(on, pad, 1e-3));
  EXPECT_FALSE(world.in_contact(pad, far, 1e-3));
  EXPECT_FALSE(world.in_contact(on, far, 1e-3));
  EXPECT_LT(world.max_penetration(), 1e-4);
}

TEST(BulletWorld, ContactToleranceCountsSmallGaps) {
  BulletWorld world(WorldOptions{});
  const int pad = world.add_body(box(0, Vec3(0, 0, 0.01), Vec3(0.2, 0.2, 0.01), 0.0));
  // 0.5 mm above the pad: touching within 1 mm, not within 0.1 mm.
  const int cube = world.add_body(box(1, Vec3(0, 0, 0.0705), Vec3(0.05, 0.05, 0.05)));
  world.detect_contacts();
  EXPECT_TRUE(world.in_contact(pad, cube, 1e-3));
  EXPECT_FALSE(world.in_contact(pad, cube, 1e-4));
  EXPECT_NEAR(world.distance(pad, cube), 5e-4, 1e-5);
}

TEST(BulletWorld, DistanceBetweenConvexAndCompoundBodies) {
  WorldOptions options;
  options.floor = false;
  BulletWorld world(options);
  const int a = world.add_body(ball(0, Vec3(0, 0, 0), 0.1));
  const int b = world.add_body(ball(1, Vec3(0.5, 0, 0), 0.1));
  EXPECT_NEAR(world.distance(a, b), 0.3, 1e-5);
  // Two cubes of half size 0.05 at x = -1 and x = 0.3 form one body; the nearer one counts.
  BodySpec pair = box(2, Vec3(0, 1, 0), Vec3(0.05, 0.05, 0.05));
  pair.parts.resize(2);
  pair.parts[0].local.position = Vec3(-20, 0, 0);
  pair.parts[1].local.position = Vec3(6, 0, 0);
  const int c = world.add_body(pair);
  // Nearest point of the compound to ball a: cube corner region at x in [0.25, 0.35], y = 0.95.
  EXPECT_NEAR(world.distance(c, a), Vec3(0.25, 0.95, 0).norm() - 0.1, 1e-4);
}

TEST(BulletWorld, MaxPenetrationMeasuresOverlapWithFloorAndBodies) {
  WorldOptions options;
  BulletWorld world(options);
  world.add_body(box(0, Vec3(0, 0, 0.03), Vec3(0.05, 0.05, 0.05)));  // 2 cm into the floor
  world.detect_contacts();
  EXPECT_NEAR(world.max_penetration(), 0.02, 1e-3);
}

TEST(BulletWorld, OverlapsTestsACandidateWithoutAddingIt) {
  BulletWorld world(WorldOptions{});
  world.add_body(ball(0, Vec3(0, 0, 1)));
  EXPECT_TRUE(world.overlaps(ball(1, Vec3(0.15, 0, 1)), 0.0));
  EXPECT_FALSE(world.overlaps(ball(1, Vec3(0.25, 0, 1)), 0.0));
  EXPECT_TRUE(world.overlaps(ball(1, Vec3(3, 0, 0.05)), 0.0)) << "below the floor";
  EXPECT_EQ(world.num_bodies(), 1);
}

TEST(BulletWorld, StaticBodiesStayAndDynamicOnesRestOnThem) {
  BulletWorld world(WorldOptions{});
  const int table = world.add_body(box(0, Vec3(0, 0, 0.5), Vec3(0.5, 0.5, 0.5), 0.0));
  const int cube = world.add_body(box(1, Vec3(0, 0, 1.2), Vec3(0.1, 0.1, 0.1)));
  for (int n = 0; n < 480; ++n) world.step();
  EXPECT_NEAR(world.pose(table).position.z(), 0.5, 1e-9);
  EXPECT_NEAR(world.pose(cube).position.z(), 1.1, 5e-3);
  EXPECT_TRUE(world.in_contact(table, cube, 1e-3));
}

TEST(BulletWorld, BallJointKeepsThePivotTogether) {
  WorldOptions options;
  options.floor = false;
  BulletWorld world(options);
  const int anchor = world.add_body(box(0, Vec3(0, 0, 1), Vec3(0.05, 0.05, 0.05), 0.0));
  const int bob = world.add_body(box(1, Vec3(0.3, 0, 1), Vec3(0.05, 0.05, 0.05)));
  const Vec3 pivot(0, 0, 1);
  world.add_ball_joint(anchor, bob, pivot);
  const Vec3 local = Vec3(-0.3, 0, 0);  // pivot in the bob's frame
  for (int n = 0; n < 240; ++n) world.step();
  const Pose p = world.pose(bob);
  EXPECT_LT((p.apply(local) - pivot).norm(), 5e-3);
  EXPECT_LT(p.position.z(), 1.0 - 0.1) << "the bob swings down";
}

TEST(BulletWorld, RejectsBadInput) {
  EXPECT_THROW(BulletWorld(WorldOptions{9.81, 0.0}), ValueError);
  BulletWorld world(WorldOptions{});
  BodySpec bad = ball(3, Vec3(0, 0, 1));
  bad.object.restitution = 1.5;
  try {
    world.add_body(bad);
    FAIL() << "restitution 1.5 accepted";
  } catch (const ValueError& e) {
    EXPECT_NE(std::string(e.what()).find("body 3 (ball_3)"), std::string::npos) << e.what();
  }
  BodySpec empty = ball(4, Vec3(0, 0, 1));
  empty.parts.clear();
  EXPECT_THROW(world.add_body(empty), ValueError);
  world.add_body(ball(5, Vec3(0, 0, 1)));
  EXPECT_THROW(world.add_ball_joint(0, 0, Vec3::Zero()), ValueError);
  EXPECT_THROW(world.add_ball_joint(0, 3, Vec3::Zero()), ValueError);
}

}  // namespace
}  // namespace dynscope
