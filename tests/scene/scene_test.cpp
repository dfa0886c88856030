// Tests of the scene data model: roles, lookups, world vertices and validation.
#include "engine/scene/scene.h"

#include <gtest/gtest.h>

#include "engine/core/error.h"

namespace dynscope {
namespace {

Scene two_object_scene(int frames) {
  Scene s;
  s.scenario = "test";
  s.dt_s = 0.1;
  for (int i = 0; i < 2; ++i) {
    Object o;
    o.id = 10 + i;
    o.name = "box" + std::to_string(i);
    o.role = i == 0 ? Role::kTarget : Role::kZone;
    o.mesh = make_box_mesh(Vec3(1, 1, 1));
    o.scale = Vec3(2, 1, 1);
    s.objects.push_back(o);
    Trajectory t;
    for (int f = 0; f < frames; ++f) {
      Pose p;
      p.position = Vec3(i * 5.0, 0, f * 0.5);
      t.poses.push_back(p);
    }
    s.trajectories.push_back(t);
  }
  s.labels["target_contacting_zone"] = std::vector<double>(static_cast<size_t>(frames), 0.0);
  return s;
}

TEST(SceneTest, RolesRoundTripByName) {
  for (Role r : {Role::kTarget, Role::kZone, Role::kProbe, Role::kOther}) {
    EXPECT_EQ(parse_role(role_name(r)), r);
  }
  EXPECT_THROW(parse_role("wall"), ValueError);
}

TEST(SceneTest, LookupsAndWorldVertices) {
  const Scene s = two_object_scene(4);
  EXPECT_EQ(s.num_frames(), 4);
  EXPECT_EQ(s.object_index(11), 1);
  EXPECT_EQ(s.object_index(99), -1);
  EXPECT_EQ(s.find_role(Role::kZone), 1);
  EXPECT_EQ(s.find_role(Role::kProbe), -1);
  const Aabb box = Aabb::of(s.world_vertices(1, 2));
  EXPECT_TRUE(box.min.isApprox(Vec3(4, -0.5, 0.5)));
  EXPECT_TRUE(box.max.isApprox(Vec3(6, 0.5, 1.5)));
  EXPECT_NO_THROW(s.validate());
}

TEST(SceneTest, ValidateNamesTheInconsistency) {
  Scene s = two_object_scene(3);
  s.trajectories[1].poses.pop_back();
  try {
    s.validate();
    FAIL();
  } catch (const ValueError& e) {
    EXPECT_NE(std::string(e.what()).find("box1"), std::string::npos) << e.what();
  }
  s = two_object_scene(3);
  s.labels["target_contacting_zone"].push_back(1.0);
  EXPECT_THROW(s.validate(), ValueError);
  s = two_object_scene(3);
  s.objects[1].id = 10;
  EXPECT_THROW(s.validate(), ValueError);
  s = two_object_scene(3);
  s.trajectories[0].poses[1].position.x() = std::nan("");
  EXPECT_THROW(s.validate(), ValueError);
  s = two_object_scene(3);
  s.dt_s = 0;
  EXPECT_THROW(s.validate(), ValueError);
}

TEST(SceneTest, DeformableObjectsUseParticles) {
  Scene s = two_object_scene(2);
  s.objects[0].rigid = false;
  s.trajectories[0].poses.clear();
  for (int f = 0; f < 2; ++f) {
    Points p = s.objects[0].mesh.vertices;
    p.array() += f;
    s.trajectories[0].particles.push_back(p);
  }
  EXPECT_NO_THROW(s.validate());
  EXPECT_TRUE(s.world_vertices(0, 1).isApprox(s.trajectories[0].particles[1]));
  s.trajectories[0].particles[1].conservativeResize(3, 3);
  EXPECT_THROW(s.validate(), ValueError);
}

}  // namespace
}  // namespace dynscope
