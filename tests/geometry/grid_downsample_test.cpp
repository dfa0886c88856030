// Tests for grid downsampling: one real input point per occupied voxel, nearest the voxel centre.
#include "engine/geometry/grid_downsample.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <string>
#include <tuple>

#include "engine/core/error.h"
#include "engine/core/rng.h"

namespace dynscope {
namespace {

using Cell = std::tuple<int32_t, int64_t, int64_t, int64_t>;

Cell cell_of(const Points& p, Eigen::Index i, double voxel, int32_t object = 0) {
  return {object, static_cast<int64_t>(std::floor(p(i, 0) / voxel)),
          static_cast<int64_t>(std::floor(p(i, 1) / voxel)),
          static_cast<int64_t>(std::floor(p(i, 2) / voxel))};
}

// Reference: group points per cell, then scan each group for the point nearest the centre.
std::vector<int32_t> brute_force(const Points& p, const std::vector<int32_t>& ids, double voxel) {
  std::map<Cell, std::vector<int32_t>> groups;
  for (Eigen::Index i = 0; i < p.rows(); ++i) {
    groups[cell_of(p, i, voxel, ids.empty() ? 0 : ids[i])].push_back(static_cast<int32_t>(i));
  }
  std::vector<int32_t> kept;
  for (const auto& [cell, members] : groups) {
    const Eigen::RowVector3d centre(voxel * (std::get<1>(cell) + 0.5),
                                    voxel * (std::get<2>(cell) + 0.5),
                                    voxel * (std::get<3>(cell) + 0.5));
    int32_t best = -1;
    double best_d = std::numeric_limits<double>::infinity();
    for (const int32_t m : members) {
      const Eigen::RowVector3d d = p.row(m) - centre;
      const double dd = d.x() * d.x() + d.y() * d.y() + d.z() * d.z();
      if (dd < best_d) {
        best_d = dd;
        best = m;
      }
    }
    kept.push_back(best);
  }
  std::sort(kept.begin(), kept.end());
  return kept;
}

Points random_points(uint64_t seed, Eigen::Index n, double lo, double hi) {
  Rng rng(seed);
  Points p(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    p.row(i) << rng.uniform(lo, hi), rng.uniform(lo, hi), rng.uniform(lo, hi);
  }
  return p;
}

TEST(GridDownsampleTest, EqualsBruteForceAndKeepsOnePointPerOccupiedVoxel) {
  for (uint64_t seed = 1; seed <= 5; ++seed) {
    // Negative coordinates check that cells use floor, not truncation toward zero.
    const Points p = random_points(seed, 2000, -1.0, 1.0);
    const double voxel = 0.2 + 0.05 * static_cast<double>(seed);
    const std::vector<int32_t> kept = grid_downsample(p, voxel);
    EXPECT_EQ(kept, brute_force(p, {}, voxel)) << "seed " << seed;
    ASSERT_TRUE(std::is_sorted(kept.begin(), kept.end()));
    std::map<Cell, int> per_cell;
    for (const int32_t i : kept) {
      ASSERT_GE(i, 0);
      ASSERT_LT(i, p.rows());
      ++per_cell[cell_of(p, i, voxel)];
    }
    std::map<Cell, int> occupied;
    for (Eigen::Index i = 0; i < p.rows(); ++i) ++occupied[cell_of(p, i, voxel)];
    EXPECT_EQ(per_cell.size(), occupied.size());
    for (const auto& [cell, count] : per_cell) EXPECT_EQ(count, 1);
  }
}

TEST(GridDownsampleTest, PicksThePointNearestTheCentreNotTheFirst) {
  Points p(3, 3);
  p << 0.01, 0.01, 0.01,  // corner of voxel [0,1)^3
      0.55, 0.45, 0.5,    // nearest the centre (0.5, 0.5, 0.5)
      0.9, 0.9, 0.9;
  EXPECT_EQ(grid_downsample(p, 1.0), std::vector<int32_t>({1}));
}

TEST(GridDownsampleTest, EqualDistancesKeepTheLowestIndex) {
  Points p(4, 3);
  p << 0.25, 0.5, 0.5, 0.75, 0.5, 0.5, 0.5, 0.25, 0.5, 0.25, 0.5, 0.5;  // all 0.25 from centre
  EXPECT_EQ(grid_downsample(p, 1.0), std::vector<int32_t>({0}));
}

TEST(GridDownsampleTest, PerObjectNeverMixesObjects) {
  const Points single = random_points(3, 400, 0.0, 1.0);
  // The same cloud twice under two object ids: each copy must be downsampled on its own.
  Points p(800, 3);
  p << single, single;
  std::vector<int32_t> ids(800, 5);
  std::fill(ids.begin() + 400, ids.end(), 2);
  const std::vector<int32_t> kept = grid_downsample_per_object(p, ids, 0.25);
  EXPECT_EQ(kept, brute_force(p, ids, 0.25));
  const std::vector<int32_t> alone = grid_downsample(single, 0.25);
  std::vector<int32_t> expected = alone;
  for (const int32_t i : alone) expected.push_back(i + 400);
  EXPECT_EQ(kept, expected);
  // Interleaved ids as well.
  Rng rng(4);
  const Points q = random_points(8, 1000, -2.0, 2.0);
  std::vector<int32_t> q_ids(1000);
  for (auto& id : q_ids) id = static_cast<int32_t>(rng.uniform_int(0, 3));
  EXPECT_EQ(grid_downsample_per_object(q, q_ids, 0.5), brute_force(q, q_ids, 0.5));
}

TEST(GridDownsampleTest, CrowdedVoxelTablesEqualBruteForce) {
  // Nearly one voxel per point, so the voxel table is close to half full and lookups probe past
  // other voxels; ids of any sign, and voxels far from the origin.
  Rng rng(12);
  for (const double offset : {0.0, -3.0e6}) {
    Points p = random_points(13, 5000, -1.0, 1.0);
    p.array() += offset;
    std::vector<int32_t> ids(5000);
    for (auto& id : ids) id = static_cast<int32_t>(rng.uniform_int(-3, 3)) * 1000003;
    EXPECT_EQ(grid_downsample_per_object(p, ids, 0.02), brute_force(p, ids, 0.02)) << offset;
    EXPECT_EQ(grid_downsample(p, 0.01), brute_force(p, {}, 0.01)) << offset;
  }
}

TEST(GridDownsampleTest, EmptyInputGivesEmptyOutput) {
  EXPECT_TRUE(grid_downsample(Points(0, 3), 0.1).empty());
  EXPECT_TRUE(grid_downsample_per_object(Points(0, 3), {}, 0.1).empty());
}

void expect_value_error(const std::function<void()>& f, const std::string& name) {
  try {
    f();
    FAIL() << "expected ValueError naming " << name;
  } catch (const ValueError& e) {
    EXPECT_EQ(e.name(), name) << e.what();
  }
}

TEST(GridDownsampleTest, BadInputsThrowNamedValueErrors) {
  const Points p = random_points(1, 10, 0.0, 1.0);
  expect_value_error([&] { grid_downsample(p, 0.0); }, "voxel");
  expect_value_error([&] { grid_downsample(p, -0.1); }, "voxel");
  expect_value_error([&] { grid_downsample(p, std::nan("")); }, "voxel");
  expect_value_error([&] { grid_downsample_per_object(p, {1, 2}, 0.1); }, "object_ids");
  Points bad = p;
  bad(4, 2) = std::numeric_limits<double>::infinity();
  expect_value_error([&] { grid_downsample(bad, 0.1); }, "points");
  bad(4, 2) = 1e300;
  expect_value_error([&] { grid_downsample(bad, 0.1); }, "voxel");
}

}  // namespace
}  // namespace dynscope
