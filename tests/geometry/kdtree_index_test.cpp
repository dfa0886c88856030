// Tests for KdIndex: exact double answers even where float distances cannot tell points apart.
#include "engine/geometry/kdtree_index.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "engine/core/error.h"
#include "engine/core/rng.h"

namespace dynscope {
namespace {

std::vector<Neighbor> brute_force(const Points& points, const Vec3& q) {
  std::vector<Neighbor> all;
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    all.push_back({squared_distance(q, points.row(i).transpose()), static_cast<int32_t>(i)});
  }
  std::sort(all.begin(), all.end(), [](const Neighbor& a, const Neighbor& b) {
    return a.sq_dist < b.sq_dist || (a.sq_dist == b.sq_dist && a.index < b.index);
  });
  return all;
}

void expect_same(const std::vector<Neighbor>& actual, const std::vector<Neighbor>& expected) {
  ASSERT_EQ(actual.size(), expected.size());
  for (size_t i = 0; i < actual.size(); ++i) {
    EXPECT_EQ(actual[i].index, expected[i].index) << "position " << i;
    EXPECT_EQ(actual[i].sq_dist, expected[i].sq_dist) << "position " << i;
  }
}

TEST(KdIndexTest, KnnAndRadiusEqualBruteForce) {
  Rng rng(1);
  Points points(500, 3);
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    points.row(i) << rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1);
  }
  const KdIndex index(points);
  std::vector<Neighbor> found;
  for (int t = 0; t < 50; ++t) {
    const Vec3 q(rng.uniform(-1.5, 1.5), rng.uniform(-1.5, 1.5), rng.uniform(-1.5, 1.5));
    std::vector<Neighbor> expected = brute_force(points, q);
    index.radius(q, 0.3, found);
    std::vector<Neighbor> within;
    for (const Neighbor& n : expected) {
      if (n.sq_dist <= 0.3 * 0.3) within.push_back(n);
    }
    expect_same(found, within);
    expected.resize(10);
    index.knn(q, 10, found);
    expect_same(found, expected);
  }
}

TEST(KdIndexTest, SeparatesDistancesFloatCannot) {
  // Ten points on a sphere of radius 1 around the query, radii differing by 1e-12: identical in
  // float, so only the double recomputation orders them (here: reverse index order).
  Points points(10, 3);
  for (int i = 0; i < 10; ++i) {
    const double r = 1.0 + 1e-12 * (10 - i);
    const double a = 0.6 * i;
    points.row(i) << r * std::cos(a), r * std::sin(a), 0.0;
  }
  const KdIndex index(points);
  std::vector<Neighbor> found;
  index.knn(Vec3::Zero(), 3, found);
  ASSERT_EQ(found.size(), 3u);
  EXPECT_EQ(found[0].index, 9);
  EXPECT_EQ(found[1].index, 8);
  EXPECT_EQ(found[2].index, 7);
  index.radius(Vec3::Zero(), 1.0 + 3.5e-12, found);
  ASSERT_EQ(found.size(), 3u);
  EXPECT_EQ(found[0].index, 9);
}

TEST(KdIndexTest, ClampsKAndHandlesEmptySets) {
  Points points(3, 3);
  points << 0, 0, 0, 1, 0, 0, 2, 0, 0;
  const KdIndex index(points);
  std::vector<Neighbor> found;
  index.knn(Vec3(2.2, 0, 0), 10, found);
  ASSERT_EQ(found.size(), 3u);
  EXPECT_EQ(found[0].index, 2);
  EXPECT_EQ(found[2].index, 0);
  index.knn(Vec3::Zero(), 0, found);
  EXPECT_TRUE(found.empty());
  const KdIndex empty(Points(0, 3));
  empty.knn(Vec3::Zero(), 4, found);
  EXPECT_TRUE(found.empty());
  empty.radius(Vec3::Zero(), 4.0, found);
  EXPECT_TRUE(found.empty());
}

TEST(KdIndexTest, RejectsNonFiniteAndHugeCoordinates) {
  Points points(2, 3);
  points << 0, 0, 0, std::numeric_limits<double>::quiet_NaN(), 0, 0;
  EXPECT_THROW(KdIndex(points, "cloud"), ValueError);
  points(1, 0) = 1e31;
  try {
    KdIndex index(points, "cloud");
    FAIL();
  } catch (const ValueError& e) {
    EXPECT_EQ(e.name(), "cloud");
  }
  points(1, 0) = 1.0;
  const KdIndex index(points);
  std::vector<Neighbor> found;
  EXPECT_THROW(index.knn(Vec3(0, std::nan(""), 0), 1, found), ValueError);
}

}  // namespace
}  // namespace dynscope
