// Mesh interaction lists: points lie on close faces, and each list respects its definition.
#include "engine/model/mesh_interaction.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <string>
#include <vector>

#include "engine/core/error.h"
#include "engine/core/rng.h"
#include "engine/geometry/interaction_points.h"
#include "engine/geometry/mesh_simplify.h"
#include "engine/scene/mesh.h"
#include "tests/bench/legacy_mesh_interaction.h"
#include "tests/model/model_test_util.h"

namespace dynscope {
namespace {

// Large faces touching between the samples of the plain lattice: only the spacing finds them, and
// every vertex of the two touching faces then takes interaction points (layer 3).
TEST(MeshInteractionTest, SpacingFindsLargeFacesTouching) {
  Points vertices(16, 3);
  const Mesh box = make_box_mesh(Vec3(3, 3, 3));
  vertices.topRows(8) = box.vertices;
  vertices.bottomRows(8) = box.vertices.rowwise() + Eigen::RowVector3d(0.5, 0.5, 3.05);
  Faces faces(24, 3);
  faces.topRows(12) = box.faces;
  faces.bottomRows(12) = box.faces.array() + 8;
  std::vector<int32_t> ids(16, 1);
  std::fill(ids.begin() + 8, ids.end(), 2);
  EXPECT_EQ(build_mesh_interaction(vertices, ids, faces, 0.2, 3, 8).size(), 0);
  const MeshInteraction mi = build_mesh_interaction(vertices, ids, faces, 0.2, 3, 8, 0.25);
  ASSERT_GT(mi.size(), 100);
  for (Eigen::Index v = 0; v < 16; ++v) {
    if (std::abs(vertices(v, 2) - 1.5) < 1e-12 || std::abs(vertices(v, 2) - 1.55) < 1e-12) {
      EXPECT_GT(mi.vertex_points.valid_count(v), 0) << "vertex " << v << " of a touching face";
    }
  }
}

TEST(MeshInteractionTest, ListsFollowTheThreeLayerDefinition) {
  const auto m = testing::make_two_boxes(0.05);
  const MeshInteraction mi = build_mesh_interaction(m.vertices, m.ids, m.faces, 0.1, 3, 8);
  ASSERT_GT(mi.size(), 0);
  std::set<int32_t> objects(mi.object_ids.begin(), mi.object_ids.end());
  EXPECT_EQ(objects, (std::set<int32_t>{1, 2}));
  for (Eigen::Index i = 0; i < mi.size(); ++i) {
    const int32_t f = mi.face[i];
    // Interaction points sit on the facing sides (x = 0.5 and x = 0.55).
    EXPECT_NEAR(std::min(std::abs(mi.points(i, 0) - 0.5), std::abs(mi.points(i, 0) - 0.55)), 0.0,
                1e-9);
    for (int c = 0; c < 3; ++c) {
      EXPECT_EQ(mi.face_vertices.index(i, c), m.faces(f, c));
      EXPECT_TRUE(mi.face_vertices.mask(i, c));
    }
    ASSERT_GT(mi.senders.valid_count(i), 0) << "every receiver has a paired sender face";
    for (Eigen::Index j = 0; j < mi.senders.k(); ++j) {
      if (!mi.senders.mask(i, j)) continue;
      EXPECT_NE(mi.object_ids[mi.senders.index(i, j)], mi.object_ids[i]);
    }
  }
  // Layer 3: a vertex sees exactly the interaction points of the faces that contain it.
  std::vector<int> on_face(static_cast<size_t>(m.faces.rows()), 0);
  for (int32_t f : mi.face) ++on_face[static_cast<size_t>(f)];
  int touching = 0;
  for (Eigen::Index v = 0; v < m.vertices.rows(); ++v) {
    int expected = 0;
    for (Eigen::Index f = 0; f < m.faces.rows(); ++f) {
      if ((m.faces.row(f).array() == v).any()) expected += on_face[static_cast<size_t>(f)];
    }
    const int count = mi.vertex_points.valid_count(v);
    EXPECT_EQ(count, expected) << "vertex " << v;
    touching += count > 0;
    for (Eigen::Index j = 0; j < count; ++j) {
      const int32_t f = mi.face[mi.vertex_points.index(v, j)];
      EXPECT_TRUE((m.faces.row(f).array() == v).any());
    }
  }
  EXPECT_GT(touching, 0);
}

// A movi-a-like mesh input: a floor slab (object 0) and `objects` spheres, boxes and cylinders of
// the scenario's sizes, turned at random and packed close so that many faces pair, each simplified
// by vertex clustering at the 0.3 sampling voxel as mesh input is.
testing::TestMesh make_movi_like_meshes(int objects, uint64_t seed) {
  Rng rng(seed);
  testing::TestMesh m;
  auto append = [&](Mesh mesh, const Quat& rotation, const Vec3& position, int32_t id) {
    mesh = simplify_vertex_clustering(mesh, 0.3);
    const Eigen::Index base = m.vertices.rows();
    m.vertices.conservativeResize(base + mesh.num_vertices(), 3);
    for (Eigen::Index v = 0; v < mesh.num_vertices(); ++v) {
      m.vertices.row(base + v) =
          (rotation * mesh.vertices.row(v).transpose() + position).transpose();
    }
    const Eigen::Index f0 = m.faces.rows();
    m.faces.conservativeResize(f0 + mesh.num_faces(), 3);
    m.faces.middleRows(f0, mesh.num_faces()) = mesh.faces.array() + static_cast<int32_t>(base);
    m.ids.insert(m.ids.end(), static_cast<size_t>(mesh.num_vertices()), id);
  };
  append(make_box_mesh(Vec3(8.0, 8.0, 0.5)), Quat::Identity(), Vec3(0, 0, -0.25), 0);
  for (int o = 0; o < objects; ++o) {
    const double size = rng.uniform(0.7, 1.4);
    Mesh mesh = o % 3 == 0   ? make_sphere_mesh(size / 2)
                : o % 3 == 1 ? make_box_mesh(Vec3(size, size, size))
                             : make_cylinder_mesh(size / 2, size);
    const Quat rotation(Eigen::AngleAxisd(
        rng.uniform(0.0, 6.3), Vec3(rng.normal(), rng.normal(), rng.normal()).normalized()));
    // Two rows of objects about one size apart, resting near the floor.
    const Vec3 position(-2.4 + 1.2 * (o % 5) + rng.uniform(-0.2, 0.2),
                        -0.6 + 1.2 * (o / 5) + rng.uniform(-0.2, 0.2), size / 2 + 0.02);
    append(mesh, rotation, position, o + 1);
  }
  return m;
}

void expect_same_list(const NeighborList& a, const NeighborList& b, const std::string& what) {
  ASSERT_EQ(a.index.rows(), b.index.rows()) << what;
  ASSERT_EQ(a.index.cols(), b.index.cols()) << what;
  EXPECT_TRUE(a.index == b.index) << what;
  EXPECT_TRUE(a.mask == b.mask) << what;
}

// The interaction points and the lists equal the previous formulation's (one sort of every sample
// pair; every candidate list sorted in full, ordered maps) exactly: the same points in the same
// order, the same k nearest senders in the same order (ties by index), every vertex's points in the
// same order. Mirror-symmetric boxes give exact distance ties; k = 2 cuts most sender lists, k = 64
// none.
TEST(MeshInteractionTest, ListsEqualTheReferenceFormulation) {
  struct Case {
    std::string name;
    testing::TestMesh mesh;
  };
  // A face collapsed to one corner: all its lattice samples coincide, one interaction point.
  testing::TestMesh collapsed = testing::make_two_boxes(0.05);
  for (Eigen::Index f = 0; f < collapsed.faces.rows(); ++f) {
    if (collapsed.ids[static_cast<size_t>(collapsed.faces(f, 0))] != 1) continue;
    if (collapsed.vertices(collapsed.faces(f, 0), 0) < 0.4) continue;  // a face on the near side
    collapsed.faces(f, 1) = collapsed.faces(f, 2) = collapsed.faces(f, 0);
    break;
  }
  std::vector<Case> cases = {{"two boxes (ties)", testing::make_two_boxes(0.05)},
                             {"a collapsed face", collapsed},
                             {"movi-like seed 1", make_movi_like_meshes(10, 1)},
                             {"movi-like seed 2", make_movi_like_meshes(7, 2)}};
  int64_t compared_points = 0;
  for (const Case& c : cases) {
    for (const double threshold : {0.1, 0.4, 0.6, 0.8}) {
      for (const int k : {2, 12, 64}) {
        const std::string what =
            c.name + ", threshold " + std::to_string(threshold) + ", k " + std::to_string(k);
        if (k == 2) {  // the interaction points themselves, once per threshold
          std::vector<int32_t> face_object;
          for (Eigen::Index f = 0; f < c.mesh.faces.rows(); ++f)
            face_object.push_back(c.mesh.ids[static_cast<size_t>(c.mesh.faces(f, 0))]);
          const InteractionPoints got =
              find_interaction_points(c.mesh.vertices, c.mesh.faces, face_object, threshold);
          const InteractionPoints want = legacy::find_interaction_points(
              c.mesh.vertices, c.mesh.faces, face_object, threshold);
          EXPECT_TRUE(got.point_a == want.point_a) << what;
          EXPECT_TRUE(got.point_b == want.point_b) << what;
          EXPECT_EQ(got.face_a, want.face_a) << what;
          EXPECT_EQ(got.face_b, want.face_b) << what;
          EXPECT_EQ(got.object_a, want.object_a) << what;
          EXPECT_EQ(got.face_pairs, want.face_pairs) << what;
        }
        const MeshInteraction got =
            build_mesh_interaction(c.mesh.vertices, c.mesh.ids, c.mesh.faces, threshold, 3, k);
        const MeshInteraction want = legacy::build_mesh_interaction(c.mesh.vertices, c.mesh.ids,
                                                                    c.mesh.faces, threshold, 3, k);
        ASSERT_EQ(got.size(), want.size()) << what;
        EXPECT_TRUE(got.points == want.points) << what;
        EXPECT_EQ(got.face, want.face) << what;
        EXPECT_EQ(got.object_ids, want.object_ids) << what;
        expect_same_list(got.face_vertices, want.face_vertices, what + ": face_vertices");
        expect_same_list(got.senders, want.senders, what + ": senders");
        expect_same_list(got.vertex_points, want.vertex_points, what + ": vertex_points");
        compared_points += got.size();
      }
    }
  }
  // The scenes pair many faces: the comparison is not over empty lists.
  EXPECT_GT(compared_points, 10000);
}

TEST(MeshInteractionTest, FarApartMeshesHaveNoInteractionPoints) {
  const auto m = testing::make_two_boxes(1.0);
  const MeshInteraction mi = build_mesh_interaction(m.vertices, m.ids, m.faces, 0.1, 3, 8);
  EXPECT_EQ(mi.size(), 0);
  EXPECT_EQ(mi.vertex_points.rows(), m.vertices.rows());
  EXPECT_EQ(mi.vertex_points.k(), 0);
}

TEST(MeshInteractionTest, RejectsBadFaces) {
  auto m = testing::make_two_boxes(0.05);
  m.faces(0, 0) = 1000;
  EXPECT_THROW(build_mesh_interaction(m.vertices, m.ids, m.faces, 0.1, 3, 8), ValueError);
}

}  // namespace
}  // namespace dynscope
