// Tests of the shape parts: closed outward meshes, exact volumes and bounds, argument checks.
#include "engine/sim/shapes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <utility>

#include "engine/core/error.h"
#include "tests/support/mesh_checks.h"

namespace dynscope {
namespace {

using test::is_closed_oriented;

TEST(GridBoxMesh, ClosedOutwardWithExactVolumeAndSurfaceVertices) {
  const Vec3 h(0.5, 1.0, 1.5);
  const Mesh m = make_grid_box_mesh(h, 4);
  EXPECT_TRUE(is_closed_oriented(m));
  EXPECT_NEAR(m.volume(), 8 * h.prod(), 1e-12);
  // Welded lattice on the surface: 6 (n+1)^2 - 12 (n+1) + 8 vertices, 12 n^2 triangles.
  EXPECT_EQ(m.num_vertices(), 6 * 25 - 12 * 5 + 8);
  EXPECT_EQ(m.num_faces(), 12 * 16);
  for (Eigen::Index i = 0; i < m.num_vertices(); ++i) {
    const Vec3 p = m.vertices.row(i).transpose();
    EXPECT_NEAR((p.cwiseAbs() - h).maxCoeff(), 0.0, 1e-12) << "vertex " << i << " not on a face";
  }
}

TEST(GridCylinderMesh, ClosedOutwardInscribed) {
  const Mesh m = make_grid_cylinder_mesh(0.3, 0.7, 32, 4, 2);
  EXPECT_TRUE(is_closed_oriented(m));
  const double exact = M_PI * 0.3 * 0.3 * 1.4;
  // An inscribed 32-gon prism: area ratio sin(2pi/32) * 32 / (2 pi).
  const double prism = 0.5 * 32 * std::sin(2 * M_PI / 32) * 0.3 * 0.3 * 1.4;
  EXPECT_NEAR(m.volume(), prism, 1e-12);
  EXPECT_LT(m.volume(), exact);
  for (Eigen::Index i = 0; i < m.num_vertices(); ++i) {
    EXPECT_LE(m.vertices.row(i).head<2>().norm(), 0.3 + 1e-12);
    EXPECT_LE(std::abs(m.vertices(i, 2)), 0.7 + 1e-12);
  }
}

// Sparse meshes keep each primitive's shape with the fewest vertices: no vertex inside a flat
// face, the same collision shape, so the same volume as the dense grid where that is exact.
TEST(PartMesh, SparseKeepsTheShapeWithoutVerticesInsideFlatFaces) {
  ShapePart box;
  box.kind = ShapeKind::kBox;
  box.half_extents = Vec3(0.5, 1.0, 1.5);
  const Mesh dense_box = part_mesh(box), sparse_box = part_mesh(box, MeshDensity::kSparse);
  EXPECT_EQ(dense_box.num_vertices(), 98);
  ASSERT_EQ(sparse_box.num_vertices(), 8);
  EXPECT_EQ(sparse_box.num_faces(), 12);
  EXPECT_TRUE(is_closed_oriented(sparse_box));
  EXPECT_NEAR(sparse_box.volume(), dense_box.volume(), 1e-12);
  for (Eigen::Index i = 0; i < 8; ++i) {
    EXPECT_NEAR((sparse_box.vertices.row(i).cwiseAbs().transpose() - box.half_extents).norm(), 0,
                1e-12)
        << "vertex " << i << " is not a corner";
  }
  ShapePart cylinder;
  cylinder.kind = ShapeKind::kCylinder;
  cylinder.half_extents = Vec3(0.3, 0.3, 0.7);
  const Mesh dense_cyl = part_mesh(cylinder),
             sparse_cyl = part_mesh(cylinder, MeshDensity::kSparse);
  EXPECT_EQ(dense_cyl.num_vertices(), 226);
  ASSERT_EQ(sparse_cyl.num_vertices(), 2 * kCylinderSegments + 2) << "two rims and two centres";
  EXPECT_TRUE(is_closed_oriented(sparse_cyl));
  EXPECT_NEAR(sparse_cyl.volume(), dense_cyl.volume(), 1e-12) << "the same inscribed prism";
  for (Eigen::Index i = 0; i < sparse_cyl.num_vertices(); ++i) {
    const double r = sparse_cyl.vertices.row(i).head<2>().norm();
    EXPECT_TRUE(std::abs(r - 0.3) < 1e-12 || r < 1e-12) << "vertex " << i << " inside a cap";
    EXPECT_NEAR(std::abs(sparse_cyl.vertices(i, 2)), 0.7, 1e-12) << "vertex " << i << " on a side";
  }
  ShapePart sphere;
  sphere.kind = ShapeKind::kSphere;
  sphere.half_extents = Vec3::Constant(0.4);
  const Mesh dense_sphere = part_mesh(sphere);
  EXPECT_EQ(dense_sphere.num_vertices(), 482);
  EXPECT_EQ(part_mesh(sphere, MeshDensity::kSparse).vertices, dense_sphere.vertices)
      << "a sphere has no flat faces: kept as it is";
  // Parts stay placed in the body frame.
  box.local.position = Vec3(1, 2, 3);
  EXPECT_NEAR((body_mesh({box}, MeshDensity::kSparse).vertices.colwise().mean() -
               Eigen::RowVector3d(1, 2, 3))
                  .norm(),
              0, 1e-12);
}

TEST(MeshDensityName, RoundTripsAndRejectsOtherNames) {
  for (MeshDensity d : {MeshDensity::kDense, MeshDensity::kSparse}) {
    EXPECT_EQ(parse_mesh_density(mesh_density_name(d), "x"), d);
  }
  try {
    parse_mesh_density("coarse", "--mesh-density");
    ADD_FAILURE() << "coarse was accepted";
  } catch (const ValueError& e) {
    EXPECT_NE(std::string(e.what()).find("--mesh-density"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("\"dense\" or \"sparse\""), std::string::npos) << e.what();
  }
}

TEST(WedgeMesh, ClosedOutwardWithPrismVolume) {
  const Mesh m = make_wedge_mesh(0.8, 0.3, 0.2);
  EXPECT_TRUE(is_closed_oriented(m));
  EXPECT_NEAR(m.volume(), 0.5 * 0.8 * 0.3 * 0.4, 1e-12);
}

TEST(MeshBuilders, RejectBadSizes) {
  EXPECT_THROW(make_grid_box_mesh(Vec3(1, 0, 1)), ValueError);
  EXPECT_THROW(make_grid_box_mesh(Vec3(1, 1, 1), 0), ValueError);
  EXPECT_THROW(make_grid_cylinder_mesh(1, 1, 2), ValueError);
  EXPECT_THROW(make_wedge_mesh(1, -1, 1), ValueError);
}

TEST(BodyVolume, MatchesFormulasWithScale) {
  ShapePart box, sphere, cylinder;
  sphere.kind = ShapeKind::kSphere;
  cylinder.kind = ShapeKind::kCylinder;
  EXPECT_NEAR(body_volume({box}, Vec3(1, 2, 3)), 8 * 6, 1e-12);
  EXPECT_NEAR(body_volume({sphere}, Vec3::Constant(0.5)), 4.0 / 3.0 * M_PI * 0.125, 1e-12);
  EXPECT_NEAR(body_volume({cylinder}, Vec3(0.5, 0.5, 2)), M_PI * 0.25 * 4, 1e-12);
  ShapePart hull;
  hull.kind = ShapeKind::kConvexHull;
  hull.hull_mesh = make_grid_box_mesh(Vec3(1, 1, 1), 1);
  EXPECT_NEAR(body_volume({hull}, Vec3(2, 2, 2)), 64, 1e-9);
}

TEST(BodyAabb, ContainsTheMeshAndIsTightForBoxes) {
  ShapePart cylinder;
  cylinder.kind = ShapeKind::kCylinder;
  const Vec3 scale(0.4, 0.4, 1.0);
  Pose pose;
  pose.position = Vec3(1, 2, 3);
  pose.rotation = Quat(Eigen::AngleAxisd(0.7, Vec3(1, 2, 0.5).normalized()));
  const Aabb box = body_aabb({cylinder}, scale, pose);
  const Aabb mesh_box = Aabb::of(pose.apply(body_mesh({cylinder}).scaled(scale).vertices));
  EXPECT_TRUE((box.min.array() <= mesh_box.min.array() + 1e-12).all());
  EXPECT_TRUE((box.max.array() >= mesh_box.max.array() - 1e-12).all());
  // The 32-gon loses at most 1 - cos(pi/32) of the radius.
  EXPECT_LT((mesh_box.min - box.min).maxCoeff(), 0.4 * (1 - std::cos(M_PI / 32)) + 1e-12);

  ShapePart cube;
  const Aabb cube_box = body_aabb({cube}, Vec3(1, 2, 3), pose);
  const Aabb cube_mesh = Aabb::of(pose.apply(body_mesh({cube}).scaled(Vec3(1, 2, 3)).vertices));
  EXPECT_TRUE(cube_box.min.isApprox(cube_mesh.min, 1e-12));
  EXPECT_TRUE(cube_box.max.isApprox(cube_mesh.max, 1e-12));
}

TEST(BodyMesh, ConcatenatesPartsInTheBodyFrame) {
  ShapePart a, b;
  a.half_extents = Vec3(0.1, 0.1, 0.1);
  b.half_extents = Vec3(0.1, 0.1, 0.1);
  b.local.position = Vec3(1, 0, 0);
  const Mesh m = body_mesh({a, b});
  const Mesh single = part_mesh(a);
  ASSERT_EQ(m.num_vertices(), 2 * single.num_vertices());
  ASSERT_EQ(m.num_faces(), 2 * single.num_faces());
  EXPECT_NEAR(m.vertices.bottomRows(single.num_vertices()).col(0).mean(), 1.0, 1e-12);
  EXPECT_EQ(m.faces.bottomRows(single.num_faces()).minCoeff(), single.num_vertices());
}

TEST(CheckPart, NamesTheBodyForBadParts) {
  ShapePart sphere;
  sphere.kind = ShapeKind::kSphere;
  try {
    check_part(sphere, Vec3(1, 2, 1), "body 7 (ball)");
    FAIL() << "non-uniform sphere accepted";
  } catch (const ValueError& e) {
    EXPECT_NE(std::string(e.what()).find("body 7 (ball)"), std::string::npos);
  }
  ShapePart rotated;
  rotated.local.rotation = Quat(Eigen::AngleAxisd(0.3, Vec3::UnitZ()));
  EXPECT_THROW(check_part(rotated, Vec3(1, 2, 1), "b"), ValueError);
  EXPECT_NO_THROW(check_part(rotated, Vec3(2, 2, 2), "b"));
  ShapePart hull;
  hull.kind = ShapeKind::kConvexHull;
  EXPECT_THROW(check_part(hull, Vec3::Ones(), "b"), ValueError);
  EXPECT_THROW(check_part(ShapePart{}, Vec3(1, -1, 1), "b"), ValueError);
}

}  // namespace
}  // namespace dynscope
