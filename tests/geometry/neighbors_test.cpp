// Tests for same-object, other-object and plain kNN: equality with brute force and edge cases.
#include "engine/geometry/neighbors.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "engine/core/error.h"
#include "engine/core/rng.h"
#include "engine/core/threads.h"
#include "engine/geometry/grid_downsample.h"
#include "tests/geometry/reference_neighbors.h"

namespace dynscope {
namespace {

using reference::brute_force_knn;
using reference::Relation;

// Objects are blobs of different sizes (one smaller than K) whose centres lie close enough for
// the relational sets to be non-trivial at the radius used below.
struct Cloud {
  Points points = Points(0, 3);
  std::vector<int32_t> ids;
};

Cloud make_cloud(uint64_t seed, const std::vector<int>& sizes, double spread = 0.3) {
  Rng rng(seed);
  Cloud c;
  int total = 0;
  for (const int n : sizes) total += n;
  c.points.resize(total, 3);
  Eigen::Index row = 0;
  for (size_t o = 0; o < sizes.size(); ++o) {
    const Vec3 centre(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    for (int i = 0; i < sizes[o]; ++i, ++row) {
      c.points.row(row) << centre.x() + spread * rng.normal(), centre.y() + spread * rng.normal(),
          centre.z() + spread * rng.normal();
      // Ids are not 0..n-1 on purpose: they are labels, not indices.
      c.ids.push_back(static_cast<int32_t>(10 * o + 3));
    }
  }
  return c;
}

void expect_equal(const NeighborList& actual, const NeighborList& expected,
                  const std::string& what) {
  ASSERT_EQ(actual.rows(), expected.rows()) << what;
  ASSERT_EQ(actual.k(), expected.k()) << what;
  for (Eigen::Index i = 0; i < actual.rows(); ++i) {
    for (Eigen::Index j = 0; j < actual.k(); ++j) {
      ASSERT_EQ(actual.index(i, j), expected.index(i, j)) << what << " row " << i << " col " << j;
      ASSERT_EQ(actual.mask(i, j), expected.mask(i, j)) << what << " row " << i << " col " << j;
    }
  }
}

// Checks structure independent of any reference: valid entries first, -1 where masked, no
// repeated index, ascending distance.
void expect_well_formed(const NeighborList& list, const Points& query, const Points& source) {
  for (Eigen::Index i = 0; i < list.rows(); ++i) {
    const int valid = list.valid_count(i);
    std::set<int32_t> seen;
    double previous = -1.0;
    for (Eigen::Index j = 0; j < list.k(); ++j) {
      if (j < valid) {
        ASSERT_EQ(list.mask(i, j), 1);
        const int32_t s = list.index(i, j);
        ASSERT_GE(s, 0);
        ASSERT_LT(s, source.rows());
        ASSERT_TRUE(seen.insert(s).second) << "duplicate neighbour in row " << i;
        const double d = reference::squared_distance(query.row(i), source.row(s));
        ASSERT_GE(d, previous);
        previous = d;
      } else {
        ASSERT_EQ(list.mask(i, j), 0);
        ASSERT_EQ(list.index(i, j), -1);
      }
    }
  }
}

TEST(NeighborsTest, RandomCloudsEqualBruteForce) {
  const int k = 8;
  const double radius = 0.35;
  for (uint64_t seed = 1; seed <= 5; ++seed) {
    const Cloud c = make_cloud(seed, {120, 3, 80, 1, 150, 40});
    const std::string what = "seed " + std::to_string(seed);
    const NeighborList same = knn_same_object(c.points, c.ids, c.points, c.ids, k);
    expect_equal(same, brute_force_knn(c.points, c.ids, c.points, c.ids, k, Relation::kSameObject),
                 what + " same");
    expect_well_formed(same, c.points, c.points);
    const NeighborList other = knn_other_objects(c.points, c.ids, c.points, c.ids, k, radius);
    expect_equal(
        other, brute_force_knn(c.points, c.ids, c.points, c.ids, k, Relation::kOtherObject, radius),
        what + " other");
    expect_well_formed(other, c.points, c.points);
    const NeighborList all = knn_all(c.points, c.points, k);
    expect_equal(all, brute_force_knn(c.points, {}, c.points, {}, k, Relation::kAll),
                 what + " all");
    expect_well_formed(all, c.points, c.points);
  }
}

TEST(NeighborsTest, RelationalSetsAreNonTrivialInTheRandomClouds) {
  // Guards the test above against a radius under which every row would be trivially masked.
  const Cloud c = make_cloud(1, {120, 3, 80, 1, 150, 40});
  const NeighborList other = knn_other_objects(c.points, c.ids, c.points, c.ids, 8, 0.35);
  int full = 0, partial = 0, empty = 0;
  for (Eigen::Index i = 0; i < other.rows(); ++i) {
    const int v = other.valid_count(i);
    full += v == 8 ? 1 : 0;
    empty += v == 0 ? 1 : 0;
    partial += (v > 0 && v < 8) ? 1 : 0;
  }
  EXPECT_GT(full, 0);
  EXPECT_GT(partial, 0);
  EXPECT_GT(empty, 0);
}

TEST(NeighborsTest, SameObjectIncludesTheQueryAndNeverLeavesItsObject) {
  const Cloud c = make_cloud(7, {50, 60});
  const NeighborList same = knn_same_object(c.points, c.ids, c.points, c.ids, 16);
  for (Eigen::Index i = 0; i < same.rows(); ++i) {
    EXPECT_EQ(same.index(i, 0), i);
    for (Eigen::Index j = 0; j < same.valid_count(i); ++j) {
      EXPECT_EQ(c.ids[same.index(i, j)], c.ids[i]);
    }
  }
}

TEST(NeighborsTest, ObjectsSmallerThanKAreMaskedNotPadded) {
  Cloud c;
  c.points.resize(5, 3);
  c.points << 0, 0, 0, 1, 0, 0, 2, 0, 0, 10, 0, 0, 11, 0, 0;
  c.ids = {4, 4, 4, 9, 9};
  const NeighborList same = knn_same_object(c.points, c.ids, c.points, c.ids, 4);
  EXPECT_EQ(same.valid_count(0), 3);
  EXPECT_EQ(same.valid_count(3), 2);
  EXPECT_EQ(same.index(0, 0), 0);
  EXPECT_EQ(same.index(0, 1), 1);
  EXPECT_EQ(same.index(0, 2), 2);
  EXPECT_EQ(same.index(0, 3), -1);
  EXPECT_EQ(same.mask(0, 3), 0);
  EXPECT_EQ(same.index(4, 0), 4);
  EXPECT_EQ(same.index(4, 1), 3);
  EXPECT_EQ(same.index(4, 2), -1);
  const NeighborList all = knn_all(c.points, c.points, 7);
  EXPECT_EQ(all.valid_count(2), 5);
  EXPECT_EQ(all.index(2, 5), -1);
}

TEST(NeighborsTest, FarApartObjectsHaveEmptyRelationalSets) {
  Cloud c = make_cloud(3, {30, 30, 30}, 0.1);
  for (Eigen::Index i = 0; i < c.points.rows(); ++i) c.points(i, 0) += 100.0 * (c.ids[i] / 10);
  const NeighborList other = knn_other_objects(c.points, c.ids, c.points, c.ids, 8, 1.0);
  for (Eigen::Index i = 0; i < other.rows(); ++i) {
    EXPECT_EQ(other.valid_count(i), 0);
    EXPECT_EQ(other.index.row(i).maxCoeff(), -1);
  }
}

TEST(NeighborsTest, RadiusIsInclusive) {
  Points q(1, 3), s(2, 3);
  q << 0, 0, 0;
  s << 0.5, 0, 0, 0.75, 0, 0;
  const NeighborList at = knn_other_objects(q, {0}, s, {1, 1}, 4, 0.5);
  EXPECT_EQ(at.valid_count(0), 1);
  EXPECT_EQ(at.index(0, 0), 0);
  const NeighborList below = knn_other_objects(q, {0}, s, {1, 1}, 4, 0.4999);
  EXPECT_EQ(below.valid_count(0), 0);
  const NeighborList zero = knn_other_objects(s, {0, 0}, s, {1, 1}, 4, 0.0);
  EXPECT_EQ(zero.index(0, 0), 0);
  EXPECT_EQ(zero.index(1, 0), 1);
  EXPECT_EQ(zero.valid_count(0), 1);
}

TEST(NeighborsTest, DuplicatePointsGiveBruteForceDistancesAndTheLowestIndices) {
  // Coordinates on a coarse lattice: many exact duplicates and many equal distances.
  Rng rng(11);
  Cloud c;
  c.points.resize(300, 3);
  for (Eigen::Index i = 0; i < c.points.rows(); ++i) {
    c.points.row(i) << static_cast<double>(rng.uniform_int(0, 3)),
        static_cast<double>(rng.uniform_int(0, 3)), static_cast<double>(rng.uniform_int(0, 2));
    c.ids.push_back(static_cast<int32_t>(rng.uniform_int(0, 2)));
  }
  const int k = 12;
  const double radius = 1.5;
  struct Case {
    const char* name;
    NeighborList actual, expected;
    Relation relation;
  };
  const Case cases[] = {
      {"same", knn_same_object(c.points, c.ids, c.points, c.ids, k),
       brute_force_knn(c.points, c.ids, c.points, c.ids, k, Relation::kSameObject),
       Relation::kSameObject},
      {"other", knn_other_objects(c.points, c.ids, c.points, c.ids, k, radius),
       brute_force_knn(c.points, c.ids, c.points, c.ids, k, Relation::kOtherObject, radius),
       Relation::kOtherObject},
      {"all", knn_all(c.points, c.points, k),
       brute_force_knn(c.points, {}, c.points, {}, k, Relation::kAll), Relation::kAll},
  };
  for (const Case& cs : cases) {
    for (Eigen::Index i = 0; i < c.points.rows(); ++i) {
      ASSERT_EQ(cs.actual.valid_count(i), cs.expected.valid_count(i)) << cs.name << " row " << i;
      for (Eigen::Index j = 0; j < cs.actual.valid_count(i); ++j) {
        const int32_t got = cs.actual.index(i, j);
        const int32_t want = cs.expected.index(i, j);
        // Each index sits at the reference distance and belongs to an allowed object.
        ASSERT_EQ(reference::squared_distance(c.points.row(i), c.points.row(got)),
                  reference::squared_distance(c.points.row(i), c.points.row(want)))
            << cs.name << " row " << i << " col " << j;
        if (cs.relation == Relation::kSameObject) {
          ASSERT_EQ(c.ids[got], c.ids[i]);
        }
        if (cs.relation == Relation::kOtherObject) {
          ASSERT_NE(c.ids[got], c.ids[i]);
        }
      }
      expect_well_formed(cs.actual, c.points, c.points);
    }
    // Equal distances resolve to the lower source index, exactly as the reference does.
    expect_equal(cs.actual, cs.expected, cs.name);
  }
}

TEST(NeighborsTest, CrossLevelQueriesEqualBruteForce) {
  for (uint64_t seed = 20; seed < 23; ++seed) {
    const Cloud fine = make_cloud(seed, {200, 5, 150, 90});
    // Coarse level: grid-downsampled fine points (downsampling queries into the fine level).
    const std::vector<int32_t> kept = grid_downsample_per_object(fine.points, fine.ids, 0.25);
    Cloud coarse;
    coarse.points.resize(static_cast<Eigen::Index>(kept.size()), 3);
    for (size_t j = 0; j < kept.size(); ++j) {
      coarse.points.row(static_cast<Eigen::Index>(j)) = fine.points.row(kept[j]);
      coarse.ids.push_back(fine.ids[kept[j]]);
    }
    ASSERT_LT(coarse.points.rows(), fine.points.rows());
    for (const int k : {1, 6, 16}) {
      const std::string what = "seed " + std::to_string(seed) + " k " + std::to_string(k);
      expect_equal(knn_same_object(coarse.points, coarse.ids, fine.points, fine.ids, k),
                   brute_force_knn(coarse.points, coarse.ids, fine.points, fine.ids, k,
                                   Relation::kSameObject),
                   what + " down");
      // Upsampling: fine queries into the coarse level.
      expect_equal(knn_same_object(fine.points, fine.ids, coarse.points, coarse.ids, k),
                   brute_force_knn(fine.points, fine.ids, coarse.points, coarse.ids, k,
                                   Relation::kSameObject),
                   what + " up");
      // The same lists with the queries given by their own index (a leaf of queries at a time).
      const ObjectIndex fine_index(fine.points, fine.ids), coarse_index(coarse.points, coarse.ids);
      expect_equal(knn_same_object(coarse_index, fine_index, k),
                   brute_force_knn(coarse.points, coarse.ids, fine.points, fine.ids, k,
                                   Relation::kSameObject),
                   what + " down, indexed queries");
      expect_equal(knn_same_object(fine_index, coarse_index, k),
                   brute_force_knn(fine.points, fine.ids, coarse.points, coarse.ids, k,
                                   Relation::kSameObject),
                   what + " up, indexed queries");
      expect_equal(knn_other_objects(fine.points, fine.ids, coarse.points, coarse.ids, k, 0.5),
                   brute_force_knn(fine.points, fine.ids, coarse.points, coarse.ids, k,
                                   Relation::kOtherObject, 0.5),
                   what + " other");
      expect_equal(knn_all(fine.points, coarse.points, k),
                   brute_force_knn(fine.points, {}, coarse.points, {}, k, Relation::kAll),
                   what + " all");
    }
  }
}

TEST(NeighborsTest, QueriesOfObjectsWithoutSourcePointsAreFullyMasked) {
  const Cloud c = make_cloud(5, {20, 20});
  Points q(2, 3);
  q << 0, 0, 0, 0.1, 0.1, 0.1;
  const std::vector<int32_t> q_ids = {999, c.ids[0]};
  const NeighborList same = knn_same_object(q, q_ids, c.points, c.ids, 4);
  EXPECT_EQ(same.valid_count(0), 0);
  EXPECT_EQ(same.index.row(0).maxCoeff(), -1);
  EXPECT_EQ(same.valid_count(1), 4);
  // An object unknown to the source sees every source point as "other".
  const NeighborList other = knn_other_objects(q, q_ids, c.points, c.ids, 4, 100.0);
  EXPECT_EQ(other.valid_count(0), 4);
}

TEST(NeighborsTest, FarFromOriginCloudsStayExact) {
  // Float coordinates near 1e4 have a spacing of ~1e-3; the answer must still be exact.
  Cloud c = make_cloud(9, {100, 100}, 1e-3);
  for (Eigen::Index i = 0; i < c.points.rows(); ++i) {
    c.points.row(i) += Eigen::RowVector3d(1.0e4, -2.0e4, 3.0e3);
  }
  expect_equal(knn_same_object(c.points, c.ids, c.points, c.ids, 8),
               brute_force_knn(c.points, c.ids, c.points, c.ids, 8, Relation::kSameObject), "same");
  expect_equal(knn_all(c.points, c.points, 8),
               brute_force_knn(c.points, {}, c.points, {}, 8, Relation::kAll), "all");
  Points far(1, 3);
  far << 1e9, 1e9, -1e9;
  expect_equal(knn_all(far, c.points, 5), brute_force_knn(far, {}, c.points, {}, 5, Relation::kAll),
               "far query");
}

TEST(NeighborsTest, EmptyInputsGiveEmptyOrMaskedRows) {
  const Points none(0, 3);
  const Cloud c = make_cloud(2, {10});
  const NeighborList no_queries = knn_same_object(none, {}, c.points, c.ids, 4);
  EXPECT_EQ(no_queries.rows(), 0);
  EXPECT_EQ(no_queries.k(), 4);
  EXPECT_EQ(knn_other_objects(none, {}, c.points, c.ids, 4, 1.0).rows(), 0);
  EXPECT_EQ(knn_all(none, c.points, 4).rows(), 0);
  const NeighborList no_source = knn_same_object(c.points, c.ids, none, {}, 4);
  EXPECT_EQ(no_source.rows(), 10);
  EXPECT_EQ(no_source.mask.cast<int>().sum(), 0);
  EXPECT_EQ(no_source.index.maxCoeff(), -1);
  EXPECT_EQ(knn_other_objects(c.points, c.ids, none, {}, 4, 1.0).mask.cast<int>().sum(), 0);
  EXPECT_EQ(knn_all(c.points, none, 4).mask.cast<int>().sum(), 0);
  EXPECT_EQ(knn_all(none, none, 2).rows(), 0);
}

template <typename F>
void expect_value_error(F&& f, const std::string& name) {
  try {
    f();
    FAIL() << "expected ValueError naming " << name;
  } catch (const ValueError& e) {
    EXPECT_EQ(e.name(), name) << e.what();
  }
}

// Indexed queries into another index of the same objects on lattices full of exact ties and
// duplicates, objects with and without trees on either side, K below and above the leaf (24) and
// the sets' sizes, and a query object without source points (its rows masked).
TEST(NeighborsTest, IndexedQueriesEqualBruteForceWithTiesAndDuplicates) {
  Cloud a, b;
  auto lattice = [](Cloud& c, int32_t id, int n, double step, const Vec3& origin, int copies) {
    for (int i = 0; i < n; ++i) {
      const Vec3 p = origin + step * Vec3(i % 5, (i / 5) % 5, i / 25);
      for (int c_i = 0; c_i < copies; ++c_i) {
        c.points.conservativeResize(c.points.rows() + 1, 3);
        c.points.row(c.points.rows() - 1) = p.transpose();
        c.ids.push_back(id);
      }
    }
  };
  lattice(a, 1, 120, 0.1, Vec3(0, 0, 0), 2);   // 240 points, every one twice: a tree
  lattice(a, 2, 20, 0.1, Vec3(5, 0, 0), 1);    // 20: no tree
  lattice(a, 3, 30, 0.1, Vec3(-5, 0, 0), 1);   // no source points
  lattice(b, 1, 60, 0.2, Vec3(0, 0, 0), 1);    // 60: a tree
  lattice(b, 2, 100, 0.05, Vec3(5, 0, 0), 1);  // 100: a tree
  lattice(b, 7, 10, 0.1, Vec3(9, 0, 0), 1);    // no queries
  const ObjectIndex a_index(a.points, a.ids), b_index(b.points, b.ids);
  for (const int k : {1, 4, 16, 30, 70, 300}) {
    const std::string what = "k " + std::to_string(k);
    expect_equal(knn_same_object(a_index, b_index, k),
                 brute_force_knn(a.points, a.ids, b.points, b.ids, k, Relation::kSameObject),
                 what + " a into b");
    expect_equal(knn_same_object(b_index, a_index, k),
                 brute_force_knn(b.points, b.ids, a.points, a.ids, k, Relation::kSameObject),
                 what + " b into a");
    expect_equal(knn_same_object(a_index, a_index, k),
                 brute_force_knn(a.points, a.ids, a.points, a.ids, k, Relation::kSameObject),
                 what + " a into itself");
  }
  expect_value_error([&] { knn_same_object(a_index, b_index, 0); }, "k");
}

TEST(NeighborsTest, SharedIndicesGiveTheSameListsAsTheOneShotFunctions) {
  const Cloud fine = make_cloud(31, {300, 7, 250, 2, 180});
  const std::vector<int32_t> kept = grid_downsample_per_object(fine.points, fine.ids, 0.2);
  Cloud coarse;
  for (const int32_t i : kept) coarse.ids.push_back(fine.ids[static_cast<size_t>(i)]);
  coarse.points = fine.points(kept, Eigen::all);
  const ObjectIndex fine_index(fine.points, fine.ids);
  const ObjectIndex coarse_index(coarse.points, coarse.ids);
  EXPECT_EQ(fine_index.size(), fine.points.rows());
  ASSERT_EQ(fine_index.objects().size(), 5u);
  EXPECT_EQ(fine_index.find(23)->global.size(), 250u);
  EXPECT_EQ(fine_index.find(14), nullptr);
  // One index per level serves every list reading that level, queried from either level.
  expect_equal(knn_same_object(fine.points, fine.ids, fine_index, 16),
               knn_same_object(fine.points, fine.ids, fine.points, fine.ids, 16), "same");
  expect_equal(knn_same_object(coarse.points, coarse.ids, fine_index, 16),
               knn_same_object(coarse.points, coarse.ids, fine.points, fine.ids, 16), "down");
  expect_equal(knn_same_object(fine.points, fine.ids, coarse_index, 16),
               knn_same_object(fine.points, fine.ids, coarse.points, coarse.ids, 16), "up");
  expect_equal(knn_other_objects(fine.points, fine.ids, fine_index, 16, 0.3),
               brute_force_knn(fine.points, fine.ids, fine.points, fine.ids, 16,
                               Relation::kOtherObject, 0.3),
               "other");
  const KdIndex all_index(coarse.points);
  expect_equal(knn_all(fine.points, all_index, 16),
               brute_force_knn(fine.points, {}, coarse.points, {}, 16, Relation::kAll), "all");
  expect_value_error([&] { knn_same_object(fine.points, coarse.ids, coarse_index, 4); },
                     "query_ids");
  expect_value_error([&] { knn_other_objects(fine.points, fine.ids, coarse_index, 4, -2.0); },
                     "radius");
  expect_value_error([&] { knn_all(fine.points, all_index, 0); }, "k");
  expect_value_error([&] { ObjectIndex(fine.points, coarse.ids); }, "source_ids");
}

TEST(NeighborsTest, ListsDoNotDependOnTheThreadCount) {
  // Enough queries for the parallel path; lattice ties make any order dependence visible.
  Cloud c = make_cloud(41, {900, 5, 700, 600}, 0.4);
  for (Eigen::Index i = 0; i < c.points.rows(); i += 3) {
    c.points.row(i) = ((c.points.row(i) * 4.0).array().round() / 4.0).matrix();
  }
  const int saved = compute_threads();
  NeighborList lists[2][3];
  for (const int threads : {1, 2}) {
    set_compute_threads(threads);
    NeighborList* out = lists[threads - 1];
    out[0] = knn_same_object(c.points, c.ids, c.points, c.ids, 16);
    out[1] = knn_other_objects(c.points, c.ids, c.points, c.ids, 16, 0.3);
    out[2] = knn_all(c.points, c.points, 16);
  }
  set_compute_threads(saved);
  const char* names[] = {"same", "other", "all"};
  for (int j = 0; j < 3; ++j) expect_equal(lists[1][j], lists[0][j], names[j]);
  expect_equal(lists[1][1],
               brute_force_knn(c.points, c.ids, c.points, c.ids, 16, Relation::kOtherObject, 0.3),
               "other vs brute force");
}

TEST(NeighborsTest, RowsByIdEqualAStableSortByIdForNarrowAndWideIds) {
  // Narrow ids take the counting sort, ids spread over a wide range the comparison sort; both
  // must give every row once, by id, ascending within an id.
  Rng rng(44);
  const std::vector<std::pair<int64_t, int64_t>> ranges = {
      {0, 7}, {-5, 5}, {1000, 1003}, {0, 0}, {-2147483647 - 1, 2147483647}, {0, 100000}};
  for (const auto& [lo, hi] : ranges) {
    for (const size_t n : {size_t{0}, size_t{1}, size_t{37}, size_t{3000}}) {
      std::vector<int32_t> ids(n);
      for (auto& id : ids) id = static_cast<int32_t>(rng.uniform_int(lo, hi));
      if (n > 2) ids[n / 2] = static_cast<int32_t>(hi);
      std::vector<int32_t> expected(n);
      for (size_t i = 0; i < n; ++i) expected[i] = static_cast<int32_t>(i);
      std::stable_sort(expected.begin(), expected.end(), [&](int32_t a, int32_t b) {
        return ids[static_cast<size_t>(a)] < ids[static_cast<size_t>(b)];
      });
      EXPECT_EQ(rows_by_id(ids), expected) << "ids in [" << lo << ", " << hi << "], n " << n;
    }
  }
}

TEST(NeighborsTest, BadInputsThrowNamedValueErrors) {
  const Cloud c = make_cloud(4, {10, 10});
  std::vector<int32_t> short_ids(c.ids.begin(), c.ids.end() - 1);
  expect_value_error([&] { knn_same_object(c.points, c.ids, c.points, c.ids, 0); }, "k");
  expect_value_error([&] { knn_all(c.points, c.points, -3); }, "k");
  expect_value_error([&] { knn_same_object(c.points, short_ids, c.points, c.ids, 4); },
                     "query_ids");
  expect_value_error([&] { knn_other_objects(c.points, c.ids, c.points, short_ids, 4, 1.0); },
                     "source_ids");
  expect_value_error([&] { knn_other_objects(c.points, c.ids, c.points, c.ids, 4, -1.0); },
                     "radius");
  expect_value_error(
      [&] {
        knn_other_objects(c.points, c.ids, c.points, c.ids, 4,
                          std::numeric_limits<double>::quiet_NaN());
      },
      "radius");
  Points bad = c.points;
  bad(3, 1) = std::numeric_limits<double>::quiet_NaN();
  expect_value_error([&] { knn_all(bad, c.points, 4); }, "query");
  expect_value_error([&] { knn_same_object(c.points, c.ids, bad, c.ids, 4); }, "source");
  bad(3, 1) = std::numeric_limits<double>::infinity();
  expect_value_error([&] { knn_all(c.points, bad, 4); }, "source");
  try {
    knn_all(bad, c.points, 4);
    FAIL();
  } catch (const ValueError& e) {
    EXPECT_NE(std::string(e.what()).find("point 3"), std::string::npos) << e.what();
  }
}

TEST(NeighborsTest, AnObjectsTreeErrorReachesTheCallerFromTheParallelBuild) {
  // Enough source points and objects for ObjectIndex to build its trees on two threads; a
  // coordinate beyond 1e18 (finite, so it passes the input check) fails one object's tree.
  Cloud c = make_cloud(43, {1200, 900, 800});
  c.points(2000, 2) = 1e19;
  const int saved = compute_threads();
  for (const int threads : {1, 2}) {
    set_compute_threads(threads);
    expect_value_error([&] { ObjectIndex(c.points, c.ids); }, "source");
    expect_value_error([&] { knn_same_object(c.points, c.ids, c.points, c.ids, 8); }, "source");
  }
  set_compute_threads(saved);
}

}  // namespace
}  // namespace dynscope
