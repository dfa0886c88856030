// Tests for the scene point cloud: deterministic, on the surface, one point per voxel, posed.
#include "engine/geometry/point_cloud.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>
#include <tuple>

#include "engine/core/error.h"

namespace dynscope {
namespace {

// A rigid box, a rigid sphere and a deformable sheet over three frames.
Scene make_scene() {
  Scene s;
  s.scenario = "test";
  Object box;
  box.id = 4;
  box.name = "box";
  box.mesh = make_box_mesh(Vec3(1, 1, 1));
  box.scale = Vec3(0.4, 0.6, 0.2);
  Object ball;
  ball.id = 9;
  ball.name = "ball";
  ball.mesh = make_sphere_mesh(0.5, 8, 12);
  Object sheet;
  sheet.id = 2;
  sheet.name = "sheet";
  sheet.rigid = false;
  sheet.mesh.vertices.resize(6, 3);
  sheet.mesh.vertices << 0, 0, 0, 0.5, 0, 0, 1, 0, 0, 0, 0.5, 0, 0.5, 0.5, 0, 1, 0.5, 0;
  sheet.mesh.faces.resize(4, 3);
  sheet.mesh.faces << 0, 1, 4, 0, 4, 3, 1, 2, 5, 1, 5, 4;
  s.objects = {box, ball, sheet};
  s.trajectories.resize(3);
  for (int f = 0; f < 3; ++f) {
    Pose p;
    p.position = Vec3(0.1 * f, -0.2 * f, 1.0 + f);
    p.rotation = Quat(Eigen::AngleAxisd(0.4 * f, Vec3(1, 2, 3).normalized()));
    s.trajectories[0].poses.push_back(p);
    p.position.x() += 2.0;
    p.rotation = Quat(Eigen::AngleAxisd(-0.3 * f, Vec3::UnitZ()));
    s.trajectories[1].poses.push_back(p);
    Points particles = sheet.mesh.vertices;
    particles.col(2).array() += 0.05 * f * particles.col(0).array();
    s.trajectories[2].particles.push_back(particles);
  }
  return s;
}

TEST(PointCloudTest, IsDeterministicAndSeedDependent) {
  const Scene scene = make_scene();
  PointCloudOptions options;
  options.voxel = 0.1;
  options.seed = 17;
  const ScenePointCloud a = build_point_cloud(scene, options);
  const ScenePointCloud b = build_point_cloud(scene, options);
  EXPECT_EQ(a.rest, b.rest);
  EXPECT_EQ(a.object, b.object);
  EXPECT_EQ(a.particle, b.particle);
  options.seed = 18;
  const ScenePointCloud c = build_point_cloud(scene, options);
  EXPECT_FALSE(c.rest.rows() == a.rest.rows() && c.rest == a.rest);
}

TEST(PointCloudTest, RigidPointsLieOnTheScaledSurfaceOnePerVoxel) {
  const Scene scene = make_scene();
  PointCloudOptions options;
  options.voxel = 0.05;
  const ScenePointCloud cloud = build_point_cloud(scene, options);
  ASSERT_EQ(cloud.object.size(), static_cast<size_t>(cloud.size()));
  ASSERT_EQ(cloud.object_id.size(), static_cast<size_t>(cloud.size()));
  ASSERT_EQ(cloud.particle.size(), static_cast<size_t>(cloud.size()));
  EXPECT_EQ(cloud.count_of(0) + cloud.count_of(1) + cloud.count_of(2), cloud.size());
  EXPECT_EQ(cloud.count_of(3), 0);
  const Vec3 half(0.2, 0.3, 0.1);
  std::set<std::tuple<int, int64_t, int64_t, int64_t>> cells;
  for (Eigen::Index i = 0; i < cloud.size(); ++i) {
    const int32_t o = cloud.object[static_cast<size_t>(i)];
    EXPECT_EQ(cloud.object_id[static_cast<size_t>(i)], scene.objects[o].id);
    const Vec3 p = cloud.rest.row(i).transpose();
    if (o == 0) {
      // On the box surface: inside the box and on at least one side.
      EXPECT_TRUE((p.cwiseAbs().array() <= half.array() + 1e-12).all());
      EXPECT_NEAR((p.cwiseAbs() - half).maxCoeff(), 0.0, 1e-12);
      EXPECT_EQ(cloud.particle[static_cast<size_t>(i)], -1);
    } else if (o == 1) {
      // On the faceted sphere: inside the circumscribed radius, and near it (8 x 12 facets
      // bring the surface no closer than about 0.9 R to the centre).
      EXPECT_LE(p.norm(), 0.5 + 1e-12);
      EXPECT_GT(p.norm(), 0.4);
    }
    const auto cell = std::make_tuple(o, static_cast<int64_t>(std::floor(p.x() / options.voxel)),
                                      static_cast<int64_t>(std::floor(p.y() / options.voxel)),
                                      static_cast<int64_t>(std::floor(p.z() / options.voxel)));
    EXPECT_TRUE(cells.insert(cell).second) << "two points of object " << o << " in one voxel";
  }
  // Dense enough that surface voxels are well covered: the box's area is 0.88, i.e. ~350
  // voxel faces of 0.05², and the point count tracks that.
  EXPECT_GT(cloud.count_of(0), 250);
  EXPECT_LT(cloud.count_of(0), 700);
}

TEST(PointCloudTest, PositionsFollowPosesAndParticles) {
  const Scene scene = make_scene();
  PointCloudOptions options;
  options.voxel = 0.1;
  const ScenePointCloud cloud = build_point_cloud(scene, options);
  ASSERT_GT(cloud.count_of(2), 0);
  for (int f = 0; f < scene.num_frames(); ++f) {
    const Points world = cloud.positions(scene, f);
    ASSERT_EQ(world.rows(), cloud.size());
    for (Eigen::Index i = 0; i < cloud.size(); ++i) {
      const int32_t o = cloud.object[static_cast<size_t>(i)];
      Vec3 expected;
      if (scene.objects[o].rigid) {
        expected = scene.trajectories[o].poses[f].apply(Vec3(cloud.rest.row(i).transpose()));
      } else {
        expected = scene.trajectories[o].particles[f].row(cloud.particle[i]).transpose();
      }
      EXPECT_LT((world.row(i).transpose() - expected).norm(), 1e-12) << "frame " << f;
    }
  }
  // Deformable rest positions are the frame-0 particles they refer to.
  for (Eigen::Index i = 0; i < cloud.size(); ++i) {
    if (cloud.object[static_cast<size_t>(i)] != 2) continue;
    EXPECT_EQ(cloud.rest.row(i), scene.trajectories[2].particles[0].row(cloud.particle[i]));
  }
}

TEST(PointCloudTest, BadInputsThrowNamedValueErrors) {
  const Scene scene = make_scene();
  auto name_of = [&](const auto& f) {
    try {
      f();
    } catch (const ValueError& e) {
      return e.name();
    }
    return std::string("no error");
  };
  PointCloudOptions bad;
  bad.voxel = 0.0;
  EXPECT_EQ(name_of([&] { build_point_cloud(scene, bad); }), "voxel");
  bad.voxel = 1e-6;
  EXPECT_EQ(name_of([&] { build_point_cloud(scene, bad); }), "voxel");
  bad.voxel = 0.1;
  bad.oversample = std::nan("");
  EXPECT_EQ(name_of([&] { build_point_cloud(scene, bad); }), "oversample");
  Scene flat = scene;
  flat.objects[1].scale = Vec3(1, 1, 0);
  flat.objects[1].mesh = make_box_mesh(Vec3(1, 1, 1));
  flat.objects[1].mesh.vertices.col(0).setZero();
  flat.objects[1].mesh.vertices.col(1).setZero();
  EXPECT_EQ(name_of([&] { build_point_cloud(flat, PointCloudOptions()); }), "object 9 (ball)");
  const ScenePointCloud cloud = build_point_cloud(scene, PointCloudOptions());
  EXPECT_EQ(name_of([&] { cloud.positions(scene, 3); }), "frame");
  EXPECT_EQ(name_of([&] { cloud.positions(scene, -1); }), "frame");
}

}  // namespace
}  // namespace dynscope
