// HierarchyCache: reused lists equal a fresh search over rigid, jittered, deformed, tied and
// replaced objects, and reuse happens where the motion is rigid.
#include "engine/model/hierarchy_cache.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "engine/core/rng.h"
#include "engine/core/threads.h"
#include "engine/model/hierarchy.h"
#include "tests/model/model_test_util.h"

namespace dynscope {
namespace {

using testing::make_scene;
using testing::TestScene;

HierarchyOptions options() { return testing::small_hierarchy_options(); }

// A random proper rotation and a translation of up to `reach` in each coordinate.
Pose random_motion(Rng& rng, double reach) {
  Pose p;
  p.rotation = Quat(rng.normal(), rng.normal(), rng.normal(), rng.normal()).normalized();
  p.position =
      Vec3(rng.uniform(-reach, reach), rng.uniform(-reach, reach), rng.uniform(0.0, reach));
  return p;
}

// Every object of `rest` moved by its own pose, point by point as the rollout's rigid projection
// writes them (R·rest + t).
Points move_objects(const TestScene& rest, const std::vector<Pose>& poses) {
  Points out(rest.points.rows(), 3);
  for (Eigen::Index i = 0; i < out.rows(); ++i) {
    const Pose& p = poses[static_cast<size_t>(rest.ids[static_cast<size_t>(i)] - 10)];
    out.row(i) = p.apply(Vec3(rest.points.row(i).transpose())).transpose();
  }
  return out;
}

// The hierarchy built with the cache equals the one built without it, list by list.
void expect_same_hierarchy(const Points& points, const std::vector<int32_t>& ids,
                           HierarchyCache& cache, const std::string& what) {
  const Hierarchy fresh = build_hierarchy(points, ids, options());
  const Hierarchy cached = build_hierarchy(points, ids, options(), &cache);
  ASSERT_EQ(cached.num_levels(), fresh.num_levels());
  for (int l = 0; l < fresh.num_levels(); ++l) {
    for (const LevelList list : kLevelLists) {
      const std::string name = what + " " + level_list_path(l, list);
      EXPECT_EQ(level_list(cached.levels[l], list).index, level_list(fresh.levels[l], list).index)
          << name;
      EXPECT_EQ(level_list(cached.levels[l], list).mask, level_list(fresh.levels[l], list).mask)
          << name;
    }
  }
}

// Query rows of the same-object lists of `h` that are searched (level 0's same list and the up
// list of every coarser level; the other same-object lists are rows of these).
int64_t list_rows(const Hierarchy& h) {
  int64_t rows = 0;
  for (int l = 0; l < h.num_levels(); ++l) rows += h.levels[l > 0 ? l - 1 : 0].points.rows();
  return rows;
}

// The level-0 same-object list of `scene` through the cache's slot 0 (every point its own origin).
NeighborList level0_list(HierarchyCache& cache, const TestScene& scene, int k = 8) {
  std::vector<int32_t> origin(scene.ids.size());
  for (size_t i = 0; i < origin.size(); ++i) origin[i] = static_cast<int32_t>(i);
  const ObjectIndex index(scene.points, scene.ids);
  const NeighborList list =
      cache.same_object_list(0, scene.points, scene.ids, origin, scene.points, index, origin, k);
  const NeighborList fresh = knn_same_object(scene.points, scene.ids, index, k);
  EXPECT_EQ(list.index, fresh.index);
  EXPECT_EQ(list.mask, fresh.mask);
  return list;
}

TEST(HierarchyCacheTest, RigidStepsReuseAlmostEveryRowAndEqualAFreshSearch) {
  const TestScene rest = make_scene(4, 150, 21);
  Rng rng(5);
  HierarchyCache cache;
  int64_t total = 0;
  for (int step = 0; step < 8; ++step) {
    const std::vector<Pose> poses = {random_motion(rng, 20.0), random_motion(rng, 20.0),
                                     random_motion(rng, 20.0), random_motion(rng, 20.0)};
    const Points moved = move_objects(rest, poses);
    expect_same_hierarchy(moved, rest.ids, cache, "step " + std::to_string(step));
    total += list_rows(build_hierarchy(moved, rest.ids, options()));
  }
  // Every row is answered once. The 600 level-0 rows are searched at the first step, anchored at
  // the second and reused nearly always after that (the coarser lists change with the voxel
  // grid's selection as the objects turn).
  EXPECT_EQ(cache.reused_rows() + cache.searched_rows(), total);
  EXPECT_GT(cache.reused_rows(), 6 * 600 * 95 / 100);
}

// Moving the whole scene in x and y keeps the grid's selection (the grid is anchored at the
// points' minimum), so every list of every level is reused.
TEST(HierarchyCacheTest, AnUnchangedSelectionReusesEveryListOfEveryLevel) {
  const TestScene rest = make_scene(4, 150, 12);
  HierarchyCache cache;
  expect_same_hierarchy(rest.points, rest.ids, cache, "first");
  const int64_t rows = list_rows(build_hierarchy(rest.points, rest.ids, options()));
  ASSERT_EQ(cache.searched_rows(), rows);
  for (int step = 1; step <= 4; ++step) {
    Points shifted = rest.points;
    shifted.col(0).array() += 0.37 * step;
    shifted.col(1).array() -= 1.1 * step;
    expect_same_hierarchy(shifted, rest.ids, cache, "shift " + std::to_string(step));
  }
  // Searched at the first step, anchored at the second (the same points came back), reused after.
  EXPECT_EQ(cache.searched_rows(), 2 * rows);
  EXPECT_EQ(cache.reused_rows(), 3 * rows);
}

TEST(HierarchyCacheTest, ThreadCountDoesNotChangeTheLists) {
  const TestScene rest = make_scene(2, 600, 4);
  Rng rng(8);
  HierarchyCache one, two;
  const int saved = compute_threads();
  for (int step = 0; step < 3; ++step) {
    const Points p = move_objects(rest, {random_motion(rng, 3.0), random_motion(rng, 3.0)});
    set_compute_threads(1);
    const Hierarchy a = build_hierarchy(p, rest.ids, options(), &one);
    set_compute_threads(2);
    const Hierarchy b = build_hierarchy(p, rest.ids, options(), &two);
    for (int l = 0; l < a.num_levels(); ++l) {
      for (const LevelList list : kLevelLists) {
        const std::string name = std::to_string(step) + " " + level_list_path(l, list);
        EXPECT_EQ(level_list(a.levels[l], list).index, level_list(b.levels[l], list).index)
            << name;
        EXPECT_EQ(level_list(a.levels[l], list).mask, level_list(b.levels[l], list).mask) << name;
      }
    }
  }
  set_compute_threads(saved);
  EXPECT_EQ(one.reused_rows(), two.reused_rows());
}

// Small deformations move distances by up to twice the jitter: rows whose neighbours are closer
// together than that are searched afresh, and the lists still equal a fresh search, although the
// lists of the anchor step no longer do.
TEST(HierarchyCacheTest, JitteredStepsSearchTheRowsTheyCannotCertify) {
  const TestScene rest = make_scene(3, 200, 9);
  Rng rng(17);
  HierarchyCache cache;
  build_hierarchy(rest.points, rest.ids, options(), &cache);
  const Hierarchy anchor = build_hierarchy(rest.points, rest.ids, options(), &cache);
  const int64_t searched_at_anchor = cache.searched_rows();
  ASSERT_EQ(searched_at_anchor, 2 * list_rows(anchor));
  ASSERT_EQ(cache.reused_rows(), 0);
  Points jittered = rest.points;
  for (Eigen::Index i = 0; i < jittered.rows(); ++i) {
    for (int d = 0; d < 3; ++d) jittered(i, d) += rng.uniform(-1e-5, 1e-5);
  }
  const Hierarchy fresh = build_hierarchy(jittered, rest.ids, options());
  EXPECT_NE(anchor.levels[0].same.index, fresh.levels[0].same.index)
      << "the jitter should reorder some neighbours, or the test proves nothing";
  expect_same_hierarchy(jittered, rest.ids, cache, "jittered");
  const int64_t searched = cache.searched_rows() - searched_at_anchor;
  EXPECT_GT(searched, 0);
  EXPECT_GT(cache.reused_rows(), 0);
}

TEST(HierarchyCacheTest, ExactTiesAreNeverReused) {
  // One object on a regular lattice: every point has several neighbours at exactly equal distance.
  TestScene lattice;
  for (int x = 0; x < 6; ++x) {
    for (int y = 0; y < 6; ++y) {
      for (int z = 0; z < 6; ++z) {
        lattice.points.conservativeResize(lattice.points.rows() + 1, 3);
        lattice.points.row(lattice.points.rows() - 1) << 0.04 * x, 0.04 * y, 0.1 + 0.04 * z;
        lattice.ids.push_back(10);
      }
    }
  }
  Rng rng(3);
  HierarchyCache cache;
  for (int step = 0; step < 4; ++step) {
    TestScene moved = lattice;
    moved.points = move_objects(lattice, {random_motion(rng, 2.0)});
    level0_list(cache, moved);
  }
  EXPECT_EQ(cache.reused_rows(), 0);
  EXPECT_EQ(cache.searched_rows(), 4 * 216);
}

TEST(HierarchyCacheTest, DeformedReplacedAndResizedObjectsAreSearchedAfresh) {
  const TestScene rest = make_scene(3, 120, 2);
  HierarchyCache cache;
  level0_list(cache, rest);
  level0_list(cache, rest);  // the same points again: anchored
  ASSERT_EQ(cache.searched_rows(), 720);
  ASSERT_EQ(cache.reused_rows(), 0);

  // Object 11 grows by 2 %: not a rigid motion, so its 120 rows are searched and anchored again;
  // the others are reused.
  TestScene grown = rest;
  for (Eigen::Index i = 120; i < 240; ++i) grown.points.row(i) *= 1.02;
  level0_list(cache, grown);
  EXPECT_EQ(cache.searched_rows(), 720 + 120);
  EXPECT_EQ(cache.reused_rows(), 240);

  // Another scene with the same sizes and ids: no rigid motion fits, nothing is reused.
  const TestScene other = make_scene(3, 120, 77);
  level0_list(cache, other);
  EXPECT_EQ(cache.searched_rows(), 720 + 120 + 360);
  EXPECT_EQ(cache.reused_rows(), 240);

  // Object 12 shrinks to 5 points, fewer than K: new points, searched (masked as without the
  // cache), anchored when they come back, then reused like the others.
  TestScene small = other;
  small.points.conservativeResize(240 + 5, 3);
  small.ids.resize(240 + 5);
  level0_list(cache, small);
  level0_list(cache, small);
  level0_list(cache, small);
  EXPECT_EQ(cache.searched_rows(), 720 + 120 + 360 + 5 + 5);
  EXPECT_EQ(cache.reused_rows(), 240 + 240 + 240 + 245);
  // The whole hierarchy of such a scene, through the cache, still equals a fresh build.
  HierarchyCache whole;
  expect_same_hierarchy(small.points, small.ids, whole, "small");
  expect_same_hierarchy(small.points, small.ids, whole, "small again");
}

}  // namespace
}  // namespace dynscope
