// Tests for KdIndex: exact double answers equal to brute force, ties, limits, tiny and far sets.
#include "engine/geometry/kdtree_index.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "engine/core/error.h"
#include "engine/core/isa_clones.h"
#include "engine/core/rng.h"
#include "engine/core/threads.h"

namespace dynscope {
namespace {

// The order every sorted answer must have: nearest first, ties by index.
bool nearer(const Neighbor& a, const Neighbor& b) {
  return a.sq_dist < b.sq_dist || (a.sq_dist == b.sq_dist && a.index < b.index);
}

std::vector<Neighbor> brute_force(const Points& points, const Vec3& q) {
  std::vector<Neighbor> all;
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    all.push_back({squared_distance(q, points.row(i).transpose()), static_cast<int32_t>(i)});
  }
  std::sort(all.begin(), all.end(), nearer);
  return all;
}

// The first k of a brute-force answer whose squared distance is at most `limit`.
std::vector<Neighbor> nearest_within(const std::vector<Neighbor>& all, size_t k, double limit) {
  std::vector<Neighbor> out;
  for (const Neighbor& n : all) {
    if (n.sq_dist <= limit && out.size() < k) out.push_back(n);
  }
  return out;
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

// Coarse lattice coordinates: many duplicates and many equal distances, so every k-th place and
// every radius boundary is a tie that only the index order can break.
Points lattice_cloud(uint64_t seed, Eigen::Index n, const Vec3& offset) {
  Rng rng(seed);
  Points points(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    points.row(i) << static_cast<double>(rng.uniform_int(0, 5)),
        static_cast<double>(rng.uniform_int(0, 5)), static_cast<double>(rng.uniform_int(0, 3));
    points.row(i) += offset.transpose();
  }
  return points;
}

TEST(KdIndexTest, TiesAndDuplicatesResolveToTheLowestIndex) {
  for (const Vec3& offset : {Vec3(0, 0, 0), Vec3(1e6, -3e6, 2.5e5)}) {
    const Points points = lattice_cloud(3, 700, offset);
    const KdIndex index(points);
    Rng rng(4);
    std::vector<Neighbor> found;
    for (int t = 0; t < 60; ++t) {
      // Half the queries sit on lattice points (distance-0 duplicates), half between them.
      Vec3 q(static_cast<double>(rng.uniform_int(0, 5)), static_cast<double>(rng.uniform_int(0, 5)),
             static_cast<double>(rng.uniform_int(0, 3)));
      if (t % 2 == 1) q += Vec3(0.5, 0.5, 0.5);
      q += offset;
      const std::vector<Neighbor> all = brute_force(points, q);
      for (const int k : {1, 5, 16, 40}) {
        index.knn(q, k, found);
        expect_same(found, std::vector<Neighbor>(all.begin(), all.begin() + k));
      }
      for (const double r : {0.0, 1.0, std::sqrt(2.0), 1.5}) {
        std::vector<Neighbor> within;
        for (const Neighbor& n : all) {
          if (n.sq_dist <= r * r) within.push_back(n);
        }
        index.radius(q, r, found);
        expect_same(found, within);
        // Unsorted: the same set (each point once), in the tree's order.
        index.radius(q, r, found, false);
        std::sort(found.begin(), found.end(), nearer);
        expect_same(found, within);
      }
    }
  }
}

// Every point's own answer from knn_self, by point; each point must be answered exactly once.
std::vector<std::vector<Neighbor>> self_answers(const KdIndex& index, int k) {
  std::vector<std::vector<Neighbor>> answers(static_cast<size_t>(index.size()));
  std::vector<int> calls(answers.size(), 0);
  std::vector<Neighbor> scratch;
  for (size_t g = 0; g < index.self_groups(); ++g) {
    index.knn_self(g, k, scratch, [&](Eigen::Index i, const Neighbor* found, size_t count) {
      answers[static_cast<size_t>(i)].assign(found, found + count);
      ++calls[static_cast<size_t>(i)];
    });
  }
  for (size_t i = 0; i < calls.size(); ++i) EXPECT_EQ(calls[i], 1) << "point " << i;
  return answers;
}

TEST(KdIndexTest, SelfQueriesEqualOneSearchPerPoint) {
  // Points on a sphere's surface (as objects are sampled), a lattice full of duplicates and
  // ties, and sets at and below the leaf size; k below, at and above a leaf's 24 points and
  // above the set's size.
  Rng rng(21);
  Points sphere(3000, 3);
  for (Eigen::Index i = 0; i < sphere.rows(); ++i) {
    const Vec3 v(rng.normal(), rng.normal(), rng.normal());
    sphere.row(i) = (0.4 * v.normalized() + Vec3(1, -2, 0.5)).transpose();
  }
  const Points clouds[] = {sphere,
                           lattice_cloud(5, 700, Vec3::Zero()),
                           lattice_cloud(6, 700, Vec3(1e6, -3e6, 2.5e5)),
                           lattice_cloud(7, 24, Vec3::Zero()),
                           lattice_cloud(8, 25, Vec3::Zero()),
                           Points(0, 3)};
  for (const Points& points : clouds) {
    const KdIndex index(points);
    EXPECT_EQ(index.self_groups() == 0, points.rows() == 0);
    for (const int k : {1, 16, 24, 40, 100}) {
      if (k == 100 && points.rows() > 30) continue;  // more than the set: only the tiny sets
      const std::vector<std::vector<Neighbor>> answers = self_answers(index, k);
      std::vector<Neighbor> expected;
      for (Eigen::Index i = 0; i < points.rows(); ++i) {
        index.knn(points.row(i).transpose(), k, expected);
        SCOPED_TRACE("n " + std::to_string(points.rows()) + " k " + std::to_string(k) + " point " +
                     std::to_string(i));
        expect_same(answers[static_cast<size_t>(i)], expected);
        if (i % 10 == 0) {  // and against brute force for a tenth of the points
          const std::vector<Neighbor> all = brute_force(points, points.row(i).transpose());
          const auto keep = std::min(all.size(), static_cast<size_t>(k));
          expect_same(answers[static_cast<size_t>(i)],
                      std::vector<Neighbor>(all.begin(), all.begin() + keep));
        }
        if (HasFatalFailure()) return;
      }
    }
    // Nothing is answered for k <= 0 or a group out of range.
    std::vector<Neighbor> scratch;
    int calls = 0;
    const auto count_calls = [&](Eigen::Index, const Neighbor*, size_t) { ++calls; };
    index.knn_self(0, 0, scratch, count_calls);
    index.knn_self(index.self_groups(), 4, scratch, count_calls);
    EXPECT_EQ(calls, 0);
  }
}

TEST(KdIndexTest, TreesBuiltOnSeveralThreadsAreExactAndAlike) {
  // 20,000 points (trees from 16k points build their top levels first and the parts below them
  // on the compute threads): three spheres' surfaces, one far from the origin, and 2 % exact
  // duplicates. Built on one thread and on two, every answer must be the same and brute force's.
  Rng rng(44);
  const Vec3 centres[] = {Vec3(0, 0, 0), Vec3(0.25, 0.1, 0), Vec3(3e4, -1e4, 5e3)};
  Points points(20000, 3);
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    if (i >= 100 && i % 50 == 0) {
      points.row(i) = points.row(rng.uniform_int(0, static_cast<int>(i) - 1));
      continue;
    }
    const Vec3 v(rng.normal(), rng.normal(), rng.normal());
    points.row(i) = (0.2 * v.normalized() + centres[i % 3]).transpose();
  }
  set_compute_threads(1);
  const KdIndex one(points);
  set_compute_threads(2);
  const KdIndex two(points);
  const std::vector<std::vector<Neighbor>> answers_one = self_answers(one, 16);
  const std::vector<std::vector<Neighbor>> answers_two = self_answers(two, 16);
  set_compute_threads(0);
  ASSERT_EQ(one.self_groups(), two.self_groups());
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    SCOPED_TRACE("point " + std::to_string(i));
    expect_same(answers_two[static_cast<size_t>(i)], answers_one[static_cast<size_t>(i)]);
    if (i % 97 == 0) {
      const std::vector<Neighbor> all = brute_force(points, points.row(i).transpose());
      expect_same(answers_one[static_cast<size_t>(i)],
                  std::vector<Neighbor>(all.begin(), all.begin() + 16));
    }
    if (HasFatalFailure()) return;
  }
  std::vector<Neighbor> found;
  for (int t = 0; t < 120; ++t) {
    const Vec3 v = Vec3(rng.normal(), rng.normal(), rng.normal()).normalized();
    const Vec3 q = centres[t % 3] + rng.uniform(0.0, 0.3) * v;
    const std::vector<Neighbor> all = brute_force(points, q);
    for (const KdIndex* index : {&one, &two}) {
      index->knn(q, 16, found);
      expect_same(found, std::vector<Neighbor>(all.begin(), all.begin() + 16));
      index->knn(q, 16, found, 0.01);
      expect_same(found, nearest_within(all, 16, 0.01));
      index->radius(q, 0.05, found);
      expect_same(found, nearest_within(all, all.size(), 0.05 * 0.05));
    }
  }
}

TEST(KdIndexTest, GeometricallySpacedPointsEqualBruteForce) {
  // Coordinates 2^-i leave a split across the middle of a box with one point on one side at
  // every level, so the median split takes over at every level; with duplicates, points on
  // every split plane, and a second axis of small steps.
  Points points(3000, 3);
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    points.row(i) << std::ldexp(1.0, -static_cast<int>(i % 1000)),
        1e-3 * static_cast<double>(i % 7), 0.0;
  }
  const KdIndex index(points);
  const std::vector<std::vector<Neighbor>> answers = self_answers(index, 16);
  std::vector<Neighbor> found;
  for (Eigen::Index i = 0; i < points.rows(); i += 37) {
    const std::vector<Neighbor> all = brute_force(points, points.row(i).transpose());
    SCOPED_TRACE("point " + std::to_string(i));
    expect_same(answers[static_cast<size_t>(i)],
                std::vector<Neighbor>(all.begin(), all.begin() + 16));
    index.knn(points.row(i).transpose(), 16, found);
    expect_same(found, std::vector<Neighbor>(all.begin(), all.begin() + 16));
    index.radius(points.row(i).transpose(), 1e-3, found);
    expect_same(found, nearest_within(all, all.size(), 1e-6));
    if (HasFatalFailure()) return;
  }
}

TEST(KdIndexTest, KnnWithinALimitKeepsOnlyPointsAtOrBelowIt) {
  const Points points = lattice_cloud(5, 400, Vec3::Zero());
  const KdIndex index(points);
  std::vector<Neighbor> found;
  for (const double limit : {0.0, 1.0, 2.0, 3.0, 100.0}) {
    const Vec3 q(2, 3, 1);
    index.knn(q, 16, found, limit);
    expect_same(found, nearest_within(brute_force(points, q), 16, limit));
  }
  index.knn(Vec3(2, 3, 1), 16, found, -1.0);
  EXPECT_TRUE(found.empty());
}

TEST(KdIndexTest, KnnWithinALimitOnSurfacesEqualsBruteForce) {
  // Limited searches on a tree: queries on, inside, beside and far from a sphere's surface, with
  // limits from none of the points to all of them.
  Rng rng(33);
  for (const Vec3& centre : {Vec3(0.3, -0.2, 0.1), Vec3(2e5, 1e5, -3e5)}) {
    Points sphere(3000, 3);
    for (Eigen::Index i = 0; i < sphere.rows(); ++i) {
      const Vec3 v(rng.normal(), rng.normal(), rng.normal());
      sphere.row(i) = (0.1 * v.normalized() + centre).transpose();
    }
    const KdIndex index(sphere);
    std::vector<Neighbor> found;
    for (int t = 0; t < 60; ++t) {
      const Vec3 v = Vec3(rng.normal(), rng.normal(), rng.normal()).normalized();
      const double r = t % 4 == 0 ? 0.0 : rng.uniform(0.02, 0.25);
      const Vec3 q = t % 5 == 0 ? Vec3(sphere.row(t).transpose()) : Vec3(centre + r * v);
      const std::vector<Neighbor> all = brute_force(sphere, q);
      for (const double limit : {0.0, 1e-4, 0.0025, 0.01, 0.04, 1.0}) {
        for (const int k : {1, 8, 16}) {
          index.knn(q, k, found, limit);
          SCOPED_TRACE("query " + std::to_string(t) + " limit " + std::to_string(limit) + " k " +
                       std::to_string(k));
          expect_same(found, nearest_within(all, static_cast<size_t>(k), limit));
          if (HasFatalFailure()) return;
        }
      }
    }
  }
}

TEST(KdIndexTest, TinySetsAndFarQueriesEqualBruteForce) {
  Rng rng(8);
  for (const Eigen::Index n : {1, 2, 11, 12, 13, 40}) {
    Points points(n, 3);
    for (Eigen::Index i = 0; i < n; ++i) {
      points.row(i) << rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1);
    }
    const KdIndex index(points);
    std::vector<Neighbor> found;
    for (const Vec3& q : {Vec3(0.1, 0.2, 0.3), Vec3(5e17, -5e17, 1.0), Vec3(1e30, 0, 0)}) {
      const std::vector<Neighbor> all = brute_force(points, q);
      index.knn(q, 16, found);
      expect_same(found,
                  std::vector<Neighbor>(all.begin(), all.begin() + std::min<Eigen::Index>(16, n)));
    }
  }
}

// `n` points on a sphere of radius 0.3 around `offset`.
Points sphere_cloud(Rng& rng, Eigen::Index n, const Vec3& offset) {
  Points out(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Vec3 v(rng.normal(), rng.normal(), rng.normal());
    out.row(i) = (0.3 * v.normalized() + offset).transpose();
  }
  return out;
}

// Query `t` of a test over `points` placed around `offset`: by turns on a lattice point, between
// lattice points, and on a point of the set.
Vec3 mixed_query(Rng& rng, int t, const Points& points, const Vec3& offset) {
  Vec3 q(static_cast<double>(rng.uniform_int(0, 5)), static_cast<double>(rng.uniform_int(0, 5)),
         static_cast<double>(rng.uniform_int(0, 3)));
  if (t % 3 == 1) q += Vec3(0.5, 0.5, 0.5);
  if (t % 3 == 2) return points.row(t % points.rows()).transpose();
  return q + offset;
}

TEST(KdIndexTest, SetsAroundTheSmallSetSizeEqualBruteForce) {
  // Sets answered by ranking every distance and sets with a tree, on both sides of the size where
  // one takes over from the other: lattice points (ties and duplicates at every place) and
  // surface points, near and far from the origin, with and without a distance limit, k from one
  // to past the set's size.
  Rng rng(31);
  for (const Eigen::Index n : {1, 2, 7, 24, 25, 31, 32, 33, 47, 48, 49, 63, 64, 65, 97}) {
    for (const Vec3& offset : {Vec3(0, 0, 0), Vec3(1e6, -3e6, 2.5e5)}) {
      const Points surface = sphere_cloud(rng, n, offset);
      const Points lattice = lattice_cloud(40 + static_cast<uint64_t>(n), n, offset);
      for (const Points& points : {lattice, surface}) {
        const KdIndex index(points);
        std::vector<Neighbor> found;
        for (int t = 0; t < 12; ++t) {
          const Vec3 q = mixed_query(rng, t, points, offset);
          const std::vector<Neighbor> all = brute_force(points, q);
          for (const int k : {1, 5, 16, 47, 100}) {
            for (const double limit : {std::numeric_limits<double>::infinity(), 2.0, 0.0}) {
              index.knn(q, k, found, limit);
              SCOPED_TRACE("n " + std::to_string(n) + " k " + std::to_string(k) + " limit " +
                           std::to_string(limit) + " query " + std::to_string(t));
              expect_same(found, nearest_within(all, static_cast<size_t>(k), limit));
              if (HasFatalFailure()) return;
            }
          }
        }
      }
    }
  }
}

TEST(KdIndexTest, RowsAnsweredTogetherEqualBruteForce) {
  // knn_rows over sets with and without a tree: lattice points (ties and duplicates, queries on
  // the points themselves) and surface points near and far from the origin, any number of queries
  // (whole runs, a partial last run), k from one to past the set's size, and queries so far out
  // that only a scan answers them mixed into a run. Under both register arrangements of the
  // small sets' ranking (eight queries per vector, or two vectors of four), whatever this CPU runs.
  for (KernelBlocking blocking : {KernelBlocking::kWide, KernelBlocking::kNarrow}) {
    set_kernel_blocking(blocking);
    SCOPED_TRACE(blocking == KernelBlocking::kWide ? "wide" : "narrow");
    Rng rng(37);
    for (const Eigen::Index n : {1, 2, 9, 16, 17, 31, 32, 47, 48, 49, 80}) {
      for (const Vec3& offset : {Vec3(0, 0, 0), Vec3(1e6, -3e6, 2.5e5)}) {
        const Points surface = sphere_cloud(rng, n, offset);
        const Points lattice = lattice_cloud(60 + static_cast<uint64_t>(n), n, offset);
        for (const Points& points : {lattice, surface}) {
          const KdIndex index(points);
          for (const size_t m : {size_t{1}, size_t{5}, size_t{8}, size_t{19}}) {
            Points queries(static_cast<Eigen::Index>(m), 3);
            for (size_t t = 0; t < m; ++t) {
              Vec3 q = mixed_query(rng, static_cast<int>(t), points, offset);
              if (m == 19 && t == 11) q = Vec3(1e30, 0, 0);
              queries.row(static_cast<Eigen::Index>(t)) = q.transpose();
            }
            for (const int k : {1, 5, 16, 100}) {
              const size_t wanted = std::min(static_cast<size_t>(k), static_cast<size_t>(n));
              std::vector<Neighbor> out(m * wanted);
              ASSERT_EQ(index.knn_rows(queries.data(), m, k, out.data()), wanted);
              for (size_t t = 0; t < m; ++t) {
                const std::vector<Neighbor> all =
                    brute_force(points, queries.row(static_cast<Eigen::Index>(t)).transpose());
                SCOPED_TRACE("n " + std::to_string(n) + " m " + std::to_string(m) + " k " +
                             std::to_string(k) + " query " + std::to_string(t));
                const auto row = out.begin() + static_cast<std::ptrdiff_t>(t * wanted);
                const auto width = static_cast<std::ptrdiff_t>(wanted);
                expect_same(std::vector<Neighbor>(row, row + width),
                            std::vector<Neighbor>(all.begin(), all.begin() + width));
                if (HasFatalFailure()) {
                  set_kernel_blocking(KernelBlocking::kAuto);
                  return;
                }
              }
            }
          }
        }
      }
    }
  }
  set_kernel_blocking(KernelBlocking::kAuto);
  const KdIndex index(lattice_cloud(3, 20, Vec3::Zero()));
  std::vector<Neighbor> out(2 * 4);
  const double bad[6] = {0, 0, 0, 0, std::nan(""), 0};
  EXPECT_THROW(index.knn_rows(bad, 2, 4, out.data()), ValueError);
  EXPECT_EQ(index.knn_rows(bad, 1, 0, out.data()), 0u);
  EXPECT_EQ(KdIndex(Points(0, 3)).knn_rows(bad, 1, 4, out.data()), 0u);
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
