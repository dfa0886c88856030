// Tests of mesh helpers and primitive shapes (closed, outward-facing, right size).
#include "engine/scene/mesh.h"

#include <gtest/gtest.h>

#include <cmath>

#include "engine/core/error.h"
#include "tests/support/mesh_checks.h"

namespace dynscope {
namespace {

using test::is_closed_oriented;

TEST(MeshTest, BoxIsClosedOutwardWithRightAreaAndVolume) {
  const Mesh box = make_box_mesh(Vec3(1, 2, 3));
  EXPECT_EQ(box.num_vertices(), 8);
  EXPECT_EQ(box.num_faces(), 12);
  EXPECT_TRUE(is_closed_oriented(box));
  EXPECT_NEAR(box.volume(), 6.0, 1e-12);
  EXPECT_NEAR(box.area(), 2 * (2 + 3 + 6), 1e-12);
}

TEST(MeshTest, SphereIsClosedOutwardAndConvergesToBall) {
  const Mesh sphere = make_sphere_mesh(2.0, 24, 48);
  EXPECT_TRUE(is_closed_oriented(sphere));
  EXPECT_NEAR(sphere.volume(), 4.0 / 3.0 * M_PI * 8, 0.5);
  EXPECT_NEAR(sphere.area(), 4 * M_PI * 4, 0.5);
  for (Eigen::Index i = 0; i < sphere.num_vertices(); ++i) {
    EXPECT_NEAR(sphere.vertices.row(i).norm(), 2.0, 1e-12);
  }
}

TEST(MeshTest, CylinderIsClosedOutward) {
  const Mesh cyl = make_cylinder_mesh(1.0, 2.0, 64);
  EXPECT_TRUE(is_closed_oriented(cyl));
  EXPECT_NEAR(cyl.volume(), M_PI * 2.0, 0.02);
}

TEST(MeshTest, ScaledMultipliesComponentwise) {
  const Mesh box = make_box_mesh(Vec3(1, 1, 1)).scaled(Vec3(2, 3, 4));
  EXPECT_NEAR(box.volume(), 24.0, 1e-12);
}

TEST(MeshTest, ValidateRejectsBadIndicesAndNaN) {
  Mesh m = make_box_mesh(Vec3(1, 1, 1));
  m.faces(3, 1) = 8;
  EXPECT_THROW(m.validate("box"), ValueError);
  m = make_box_mesh(Vec3(1, 1, 1));
  m.vertices(2, 0) = std::nan("");
  try {
    m.validate("my box");
    FAIL();
  } catch (const ValueError& e) {
    EXPECT_NE(std::string(e.what()).find("my box"), std::string::npos);
  }
  EXPECT_THROW(make_sphere_mesh(1.0, 1, 2), ValueError);
}

}  // namespace
}  // namespace dynscope
