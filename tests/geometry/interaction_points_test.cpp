// Tests for interaction points: touching cubes pair their touching sides, distant ones nothing.
#include "engine/geometry/interaction_points.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "engine/core/error.h"
#include "engine/core/rng.h"
#include "engine/scene/mesh.h"

namespace dynscope {
namespace {

// Several meshes placed in the world, concatenated into one vertex/face set.
struct World {
  Points vertices = Points(0, 3);
  Faces faces = Faces(0, 3);
  std::vector<int32_t> face_object;

  void add(const Mesh& mesh, const Vec3& offset, int32_t object) {
    const Eigen::Index v0 = vertices.rows(), f0 = faces.rows();
    vertices.conservativeResize(v0 + mesh.num_vertices(), 3);
    faces.conservativeResize(f0 + mesh.num_faces(), 3);
    for (Eigen::Index v = 0; v < mesh.num_vertices(); ++v) {
      vertices.row(v0 + v) = mesh.vertices.row(v) + offset.transpose();
    }
    faces.bottomRows(mesh.num_faces()) = mesh.faces.array() + static_cast<int32_t>(v0);
    face_object.insert(face_object.end(), static_cast<size_t>(mesh.num_faces()), object);
  }
};

// Reference: every lattice sample against every other, O(S²).
// With `spacing` > 0 a face of longest edge L gets max(lattice, ceil(L / spacing)) subdivisions.
std::vector<std::tuple<int32_t, int32_t, int32_t, int32_t>> brute_force(const World& w,
                                                                        double threshold,
                                                                        int lattice,
                                                                        double spacing = 0.0) {
  std::vector<Eigen::RowVector3d> samples;
  std::vector<int32_t> face;
  for (Eigen::Index f = 0; f < w.faces.rows(); ++f) {
    const Eigen::RowVector3d a = w.vertices.row(w.faces(f, 0)), b = w.vertices.row(w.faces(f, 1)),
                             c = w.vertices.row(w.faces(f, 2));
    int n = lattice;
    if (spacing > 0) {
      const double longest = std::max({(a - b).norm(), (b - c).norm(), (c - a).norm()});
      n = std::max(lattice, static_cast<int>(std::ceil(longest / spacing)));
    }
    for (int i = 0; i <= n; ++i) {
      for (int j = 0; j <= n - i; ++j) {
        const int k = n - i - j;
        samples.push_back((i * a + j * b + k * c) / n);
        face.push_back(static_cast<int32_t>(f));
      }
    }
  }
  std::vector<std::tuple<int32_t, int32_t, int32_t, int32_t>> pairs;
  for (size_t a = 0; a < samples.size(); ++a) {
    for (size_t b = 0; b < samples.size(); ++b) {
      if (w.face_object[face[a]] >= w.face_object[face[b]]) continue;
      const Eigen::RowVector3d d = samples[a] - samples[b];
      if (d.x() * d.x() + d.y() * d.y() + d.z() * d.z() < threshold * threshold) {
        pairs.emplace_back(static_cast<int32_t>(a), static_cast<int32_t>(b), face[a], face[b]);
      }
    }
  }
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

// A spacing subdivides large faces until their samples are at most that far apart along the
// edges (the paper samples faces uniformly): two 8-vertex boxes of side 3, face to face 0.05
// apart and shifted by half the coarse lattice's step, share no sample pair on the lattice of 3
// subdivisions (its samples 0.7 apart) but pair all over their touching faces with the spacing.
TEST(InteractionPointsTest, SpacingSamplesLargeFacesAsDenselyAsSmallOnes) {
  EXPECT_EQ(face_lattice(1.0, 3, 0.0), 3);
  EXPECT_EQ(face_lattice(1.0, 3, 0.5), 3) << "a small face keeps the lattice";
  EXPECT_EQ(face_lattice(2.8, 3, 0.3), 10);
  EXPECT_EQ(face_lattice(1e12, 3, 0.3), 256) << "capped";
  World w;
  w.add(make_box_mesh(Vec3(3, 3, 3)), Vec3::Zero(), 0);
  w.add(make_box_mesh(Vec3(3, 3, 3)), Vec3(0.5, 0.5, 3.05), 1);
  ASSERT_EQ(w.vertices.rows(), 16);
  const double threshold = 0.2;
  EXPECT_EQ(find_interaction_points(w.vertices, w.faces, w.face_object, threshold).size(), 0u);
  const InteractionPoints ip =
      find_interaction_points(w.vertices, w.faces, w.face_object, threshold, 3, 0.25);
  const auto want = brute_force(w, threshold, 3, 0.25);
  ASSERT_GT(want.size(), 100u);
  ASSERT_EQ(ip.size(), want.size());
  for (size_t p = 0; p < ip.size(); ++p) {
    EXPECT_EQ(std::make_tuple(ip.sample_a[p], ip.sample_b[p], ip.face_a[p], ip.face_b[p]), want[p])
        << "pair " << p;
    // Every pair joins A's top (z = 1.5) to B's bottom (z = 1.55).
    EXPECT_NEAR(ip.point_a(p, 2), 1.5, 1e-12);
    EXPECT_NEAR(ip.point_b(p, 2), 1.55, 1e-12);
  }
  // Spacing 0 is the plain lattice; a negative or non-finite spacing is refused.
  EXPECT_EQ(find_interaction_points(w.vertices, w.faces, w.face_object, 0.8, 3, 0.0).face_pairs,
            find_interaction_points(w.vertices, w.faces, w.face_object, 0.8).face_pairs);
  for (const double bad : {-0.1, std::nan("")}) {
    try {
      find_interaction_points(w.vertices, w.faces, w.face_object, threshold, 3, bad);
      ADD_FAILURE() << "spacing " << bad << " was accepted";
    } catch (const ValueError& e) {
      EXPECT_NE(std::string(e.what()).find("spacing"), std::string::npos) << e.what();
    }
  }
}

TEST(InteractionPointsTest, TouchingCubesPairTheirTouchingSides) {
  // Unit cube A at the origin and a half-size cube B resting against A's +x side (x = 0.5).
  World w;
  w.add(make_box_mesh(Vec3(1, 1, 1)), Vec3::Zero(), 0);
  w.add(make_box_mesh(Vec3(0.5, 0.5, 0.5)), Vec3(0.75, 0, 0), 1);
  // Lattice spacing is 1/3 on A and 1/6 on B, so the nearest samples are 1/12 apart in-plane.
  const double threshold = 0.15;
  const InteractionPoints ip =
      find_interaction_points(w.vertices, w.faces, w.face_object, threshold);
  ASSERT_GT(ip.size(), 0u);
  ASSERT_EQ(ip.point_a.rows(), static_cast<Eigen::Index>(ip.size()));
  ASSERT_EQ(ip.point_b.rows(), static_cast<Eigen::Index>(ip.size()));
  // make_box_mesh: faces 10 and 11 are +x, faces 8 and 9 are -x (B's start at index 12).
  bool minus_x_of_b = false;
  for (size_t p = 0; p < ip.size(); ++p) {
    EXPECT_EQ(ip.object_a[p], 0);
    EXPECT_EQ(ip.object_b[p], 1);
    EXPECT_TRUE(ip.face_a[p] == 10 || ip.face_a[p] == 11) << "face_a " << ip.face_a[p];
    EXPECT_GE(ip.face_b[p], 12);
    minus_x_of_b = minus_x_of_b || ip.face_b[p] == 12 + 8 || ip.face_b[p] == 12 + 9;
    const auto row = static_cast<Eigen::Index>(p);
    EXPECT_LT((ip.point_a.row(row) - ip.point_b.row(row)).norm(), threshold);
    EXPECT_NEAR(ip.point_a(row, 0), 0.5, 1e-12);
    EXPECT_NEAR(ip.point_b(row, 0), 0.5, threshold);
  }
  EXPECT_TRUE(minus_x_of_b);
  // face_pairs: sorted, distinct, and exactly the pairs that occur.
  std::set<std::pair<int32_t, int32_t>> occurring;
  for (size_t p = 0; p < ip.size(); ++p) occurring.emplace(ip.face_a[p], ip.face_b[p]);
  const std::vector<std::pair<int32_t, int32_t>> expected(occurring.begin(), occurring.end());
  EXPECT_EQ(expected, ip.face_pairs);
}

TEST(InteractionPointsTest, DistantCubesHaveNone) {
  World w;
  w.add(make_box_mesh(Vec3(1, 1, 1)), Vec3::Zero(), 0);
  w.add(make_box_mesh(Vec3(1, 1, 1)), Vec3(1.2, 0, 0), 1);
  const InteractionPoints ip = find_interaction_points(w.vertices, w.faces, w.face_object, 0.1);
  EXPECT_EQ(ip.size(), 0u);
  EXPECT_TRUE(ip.face_pairs.empty());
  EXPECT_EQ(ip.point_a.rows(), 0);
}

TEST(InteractionPointsTest, EmptyAndSingleObjectInputsHaveNone) {
  EXPECT_EQ(find_interaction_points(Points(0, 3), Faces(0, 3), {}, 0.1).size(), 0u);
  World w;
  w.add(make_sphere_mesh(0.5), Vec3::Zero(), 0);
  EXPECT_EQ(find_interaction_points(w.vertices, w.faces, w.face_object, 10.0).size(), 0u);
}

TEST(InteractionPointsTest, ObjectOrderFollowsIdsNotFaceOrder) {
  // The first mesh has the larger id, so it becomes side b.
  World w;
  w.add(make_box_mesh(Vec3(1, 1, 1)), Vec3::Zero(), 7);
  w.add(make_box_mesh(Vec3(0.5, 0.5, 0.5)), Vec3(0.75, 0, 0), 3);
  const InteractionPoints ip = find_interaction_points(w.vertices, w.faces, w.face_object, 0.15);
  ASSERT_GT(ip.size(), 0u);
  for (size_t p = 0; p < ip.size(); ++p) {
    EXPECT_EQ(ip.object_a[p], 3);
    EXPECT_EQ(ip.object_b[p], 7);
    EXPECT_GE(ip.face_a[p], 12);
    EXPECT_LT(ip.face_b[p], 12);
  }
}

TEST(InteractionPointsTest, EqualsBruteForceOnRandomCloseMeshes) {
  for (uint64_t seed = 1; seed <= 4; ++seed) {
    Rng rng(seed);
    World w;
    for (int32_t o = 0; o < 3; ++o) {
      const Vec3 offset(rng.uniform(-0.3, 0.3), rng.uniform(-0.3, 0.3), rng.uniform(-0.3, 0.3));
      w.add(make_sphere_mesh(0.3 + 0.1 * o, 4, 6), offset, o);
    }
    const int lattice = 2 + static_cast<int>(seed % 2);
    const double threshold = 0.08;
    const InteractionPoints ip =
        find_interaction_points(w.vertices, w.faces, w.face_object, threshold, lattice);
    const auto expected = brute_force(w, threshold, lattice);
    ASSERT_EQ(ip.size(), expected.size()) << "seed " << seed;
    ASSERT_GT(ip.size(), 0u);
    std::vector<std::pair<int32_t, int32_t>> face_pairs;
    for (size_t p = 0; p < ip.size(); ++p) {
      EXPECT_EQ(ip.sample_a[p], std::get<0>(expected[p])) << "pair " << p;
      EXPECT_EQ(ip.sample_b[p], std::get<1>(expected[p])) << "pair " << p;
      EXPECT_EQ(ip.face_a[p], std::get<2>(expected[p])) << "pair " << p;
      EXPECT_EQ(ip.face_b[p], std::get<3>(expected[p])) << "pair " << p;
      face_pairs.emplace_back(ip.face_a[p], ip.face_b[p]);
      EXPECT_EQ(ip.object_a[p], w.face_object[ip.face_a[p]]);
      EXPECT_EQ(ip.object_b[p], w.face_object[ip.face_b[p]]);
      EXPECT_LT(ip.object_a[p], ip.object_b[p]);
    }
    std::sort(face_pairs.begin(), face_pairs.end());
    face_pairs.erase(std::unique(face_pairs.begin(), face_pairs.end()), face_pairs.end());
    EXPECT_EQ(ip.face_pairs, face_pairs) << "the distinct face pairs, ascending";
  }
}

TEST(InteractionPointsTest, IsDeterministic) {
  World w;
  w.add(make_sphere_mesh(0.5), Vec3::Zero(), 0);
  w.add(make_cylinder_mesh(0.3, 1.0), Vec3(0.75, 0.1, 0), 1);
  const InteractionPoints a = find_interaction_points(w.vertices, w.faces, w.face_object, 0.06);
  const InteractionPoints b = find_interaction_points(w.vertices, w.faces, w.face_object, 0.06);
  ASSERT_GT(a.size(), 0u);
  EXPECT_EQ(a.face_a, b.face_a);
  EXPECT_EQ(a.face_b, b.face_b);
  EXPECT_EQ(a.point_a, b.point_a);
  EXPECT_EQ(a.point_b, b.point_b);
}

TEST(InteractionPointsTest, BadInputsThrowNamedValueErrors) {
  World w;
  w.add(make_box_mesh(Vec3(1, 1, 1)), Vec3::Zero(), 0);
  auto name_of = [&](const Points& v, const Faces& f, const std::vector<int32_t>& ids,
                     double threshold, int lattice) {
    try {
      find_interaction_points(v, f, ids, threshold, lattice);
    } catch (const ValueError& e) {
      return e.name();
    }
    return std::string("no error");
  };
  EXPECT_EQ(name_of(w.vertices, w.faces, {0, 0}, 0.1, 3), "face_object");
  EXPECT_EQ(name_of(w.vertices, w.faces, w.face_object, 0.0, 3), "threshold");
  EXPECT_EQ(name_of(w.vertices, w.faces, w.face_object, 0.1, 0), "lattice");
  Faces bad = w.faces;
  bad(0, 0) = 8;
  EXPECT_EQ(name_of(w.vertices, bad, w.face_object, 0.1, 3), "faces");
  Points nan = w.vertices;
  nan(2, 2) = std::nan("");
  EXPECT_EQ(name_of(nan, w.faces, w.face_object, 0.1, 3), "vertices");
}

}  // namespace
}  // namespace dynscope
