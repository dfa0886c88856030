// Tests of max_penetration(): overlap depth between objects and with the floor, concave bodies.
#include "engine/sim/scene_checks.h"

#include <gtest/gtest.h>

#include "engine/core/error.h"
#include "engine/sim/shapes.h"

namespace dynscope {
namespace {

void add_cube(Scene& scene, const Vec3& position, double half, const Mesh& mesh = Mesh{}) {
  Object o;
  o.id = static_cast<int32_t>(scene.objects.size());
  o.name = "cube_" + std::to_string(o.id);
  o.mesh = mesh.empty() ? make_grid_box_mesh(Vec3::Ones(), 2) : mesh;
  o.scale = Vec3::Constant(half);
  scene.objects.push_back(o);
  Trajectory t;
  t.poses.push_back(Pose{position, Quat::Identity()});
  scene.trajectories.push_back(t);
}

TEST(MaxPenetration, MeasuresOverlapBetweenObjects) {
  Scene scene;
  add_cube(scene, Vec3(0, 0, 1), 0.1);
  add_cube(scene, Vec3(0.17, 0, 1), 0.1);  // 3 cm overlap along x
  EXPECT_NEAR(max_penetration(scene, 0), 0.03, 1e-3);
}

TEST(MaxPenetration, ZeroForSeparatedOrTouchingObjects) {
  Scene scene;
  add_cube(scene, Vec3(0, 0, 0.1), 0.1);    // resting on the floor
  add_cube(scene, Vec3(0.2, 0, 0.1), 0.1);  // touching the first one
  add_cube(scene, Vec3(1, 1, 1), 0.1);
  EXPECT_LT(max_penetration(scene, 0), 1e-4);
}

TEST(MaxPenetration, MeasuresSinkingIntoTheFloorUnlessDisabled) {
  Scene scene;
  add_cube(scene, Vec3(0, 0, 0.08), 0.1);
  EXPECT_NEAR(max_penetration(scene, 0), 0.02, 1e-3);
  EXPECT_LT(max_penetration(scene, 0, /*floor=*/false), 1e-9);
}

TEST(MaxPenetration, ConcaveBodyMadeOfPartsIsNotItsHull) {
  // Two separate unit cubes 3 apart form one object; a small cube sits in the gap between them.
  ShapePart left, right;
  left.local.position = Vec3(-1.5, 0, 0);
  right.local.position = Vec3(1.5, 0, 0);
  Scene scene;
  add_cube(scene, Vec3(0, 0, 2), 0.1, body_mesh({left, right}));
  add_cube(scene, Vec3(0, 0, 2), 0.04);
  EXPECT_LT(max_penetration(scene, 0), 1e-9);
}

TEST(MaxPenetration, RejectsFramesOutOfRange) {
  Scene scene;
  add_cube(scene, Vec3(0, 0, 1), 0.1);
  EXPECT_THROW(max_penetration(scene, 1), ValueError);
  EXPECT_THROW(max_penetration(scene, -1), ValueError);
}

}  // namespace
}  // namespace dynscope
