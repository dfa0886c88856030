// Mesh interaction lists: points lie on close faces, and each list respects its definition.
#include "engine/model/mesh_interaction.h"

#include <gtest/gtest.h>

#include <set>

#include "engine/core/error.h"
#include "tests/model/model_test_util.h"

namespace dynscope {
namespace {

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
