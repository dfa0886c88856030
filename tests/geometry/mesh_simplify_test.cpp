// Tests for vertex-clustering simplification: fewer vertices, same extent, clean faces.
#include "engine/geometry/mesh_simplify.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <set>

#include "engine/core/error.h"

namespace dynscope {
namespace {

// Box with every side split into n × n quads (two triangles each), vertices shared.
Mesh subdivided_box(const Vec3& size, int n) {
  Mesh m;
  std::vector<Vec3> vertices;
  std::vector<std::array<int32_t, 3>> faces;
  auto vertex = [&](const Vec3& p) {
    for (size_t i = 0; i < vertices.size(); ++i) {
      if ((vertices[i] - p).norm() < 1e-12) return static_cast<int32_t>(i);
    }
    vertices.push_back(p);
    return static_cast<int32_t>(vertices.size() - 1);
  };
  for (int axis = 0; axis < 3; ++axis) {
    for (const double side : {-0.5, 0.5}) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      auto at = [&](int i, int j) {
        Vec3 p;
        p[axis] = side * size[axis];
        p[u] = (static_cast<double>(i) / n - 0.5) * size[u];
        p[v] = (static_cast<double>(j) / n - 0.5) * size[v];
        return vertex(p);
      };
      for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) {
          const int32_t a = at(i, j), b = at(i + 1, j), c = at(i + 1, j + 1), d = at(i, j + 1);
          faces.push_back({a, b, c});
          faces.push_back({a, c, d});
        }
      }
    }
  }
  m.vertices.resize(static_cast<Eigen::Index>(vertices.size()), 3);
  for (size_t i = 0; i < vertices.size(); ++i) {
    m.vertices.row(static_cast<Eigen::Index>(i)) = vertices[i].transpose();
  }
  m.faces.resize(static_cast<Eigen::Index>(faces.size()), 3);
  for (size_t f = 0; f < faces.size(); ++f) {
    m.faces.row(static_cast<Eigen::Index>(f)) << faces[f][0], faces[f][1], faces[f][2];
  }
  return m;
}

void expect_clean(const Mesh& m) {
  ASSERT_NO_THROW(m.validate("simplified"));
  std::set<std::array<int32_t, 3>> seen;
  std::vector<bool> used(static_cast<size_t>(m.num_vertices()), false);
  const Eigen::VectorXd areas = m.face_areas();
  for (Eigen::Index f = 0; f < m.num_faces(); ++f) {
    std::array<int32_t, 3> tri{m.faces(f, 0), m.faces(f, 1), m.faces(f, 2)};
    EXPECT_NE(tri[0], tri[1]);
    EXPECT_NE(tri[1], tri[2]);
    EXPECT_NE(tri[0], tri[2]);
    EXPECT_GT(areas[f], 0.0);
    for (const int32_t v : tri) used[static_cast<size_t>(v)] = true;
    std::sort(tri.begin(), tri.end());
    EXPECT_TRUE(seen.insert(tri).second) << "duplicate face " << f;
  }
  for (size_t v = 0; v < used.size(); ++v) EXPECT_TRUE(used[v]) << "unreferenced vertex " << v;
}

TEST(MeshSimplifyTest, SubdividedBoxLosesVerticesButKeepsItsExtent) {
  const Vec3 size(1.0, 0.6, 0.8);
  const Mesh fine = subdivided_box(size, 12);
  ASSERT_EQ(fine.num_vertices(), 6 * 12 * 12 + 2);
  const double voxel = 0.15;
  const Mesh coarse = simplify_vertex_clustering(fine, voxel);
  expect_clean(coarse);
  EXPECT_LT(coarse.num_vertices(), fine.num_vertices() / 4);
  EXPECT_GT(coarse.num_faces(), 12);
  const Aabb before = Aabb::of(fine.vertices), after = Aabb::of(coarse.vertices);
  // Cluster means stay inside their voxel, so the box shrinks by less than one voxel per side.
  EXPECT_TRUE((after.min - before.min).cwiseAbs().maxCoeff() < voxel);
  EXPECT_TRUE((after.max - before.max).cwiseAbs().maxCoeff() < voxel);
  EXPECT_TRUE((after.min.array() >= before.min.array() - 1e-12).all());
  EXPECT_TRUE((after.max.array() <= before.max.array() + 1e-12).all());
  // The surface stays roughly the same size (clustering cuts corners, it does not collapse).
  EXPECT_GT(coarse.area(), 0.7 * fine.area());
  EXPECT_LT(coarse.area(), 1.05 * fine.area());
}

TEST(MeshSimplifyTest, TinyVoxelKeepsTheMesh) {
  const Mesh box = make_box_mesh(Vec3(1, 2, 3));
  const Mesh same = simplify_vertex_clustering(box, 0.01);
  EXPECT_EQ(same.num_vertices(), box.num_vertices());
  EXPECT_EQ(same.num_faces(), box.num_faces());
  EXPECT_NEAR(same.area(), box.area(), 1e-12);
  expect_clean(same);
}

TEST(MeshSimplifyTest, HugeVoxelCollapsesEverything) {
  const Mesh box = make_box_mesh(Vec3(1, 1, 1));
  // Shift into one voxel (the grid is anchored at the origin, the box straddles it).
  Mesh shifted = box;
  shifted.vertices.rowwise() += Eigen::RowVector3d(5, 5, 5);
  const Mesh none = simplify_vertex_clustering(shifted, 100.0);
  EXPECT_EQ(none.num_faces(), 0);
  EXPECT_EQ(none.num_vertices(), 0);
}

TEST(MeshSimplifyTest, DropsUnreferencedVerticesAndDuplicateFaces) {
  Mesh m;
  m.vertices.resize(5, 3);
  m.vertices << 0, 0, 0, 1, 0, 0, 0, 1, 0, 1.01, 0.01, 0, 7, 7, 7;  // 3 merges into 1; 4 unused
  m.faces.resize(2, 3);
  m.faces << 0, 1, 2, 0, 2, 3;  // the second face becomes the first with opposite winding
  const Mesh out = simplify_vertex_clustering(m, 0.5);
  EXPECT_EQ(out.num_vertices(), 3);
  ASSERT_EQ(out.num_faces(), 1);
  expect_clean(out);
  // The merged vertex is the mean of its cluster, and the stray vertex did not join any mean.
  EXPECT_TRUE(out.vertices.row(out.faces(0, 1)).isApprox(Eigen::RowVector3d(1.005, 0.005, 0)));
}

TEST(MeshSimplifyTest, BadInputsThrowNamedValueErrors) {
  const Mesh box = make_box_mesh(Vec3(1, 1, 1));
  try {
    simplify_vertex_clustering(box, 0.0);
    FAIL();
  } catch (const ValueError& e) {
    EXPECT_EQ(e.name(), "voxel");
  }
  EXPECT_THROW(simplify_vertex_clustering(box, -1.0), ValueError);
  Mesh broken = box;
  broken.faces(3, 1) = 99;
  try {
    simplify_vertex_clustering(broken, 0.1);
    FAIL();
  } catch (const ValueError& e) {
    EXPECT_EQ(e.name(), "mesh");
  }
}

}  // namespace
}  // namespace dynscope
