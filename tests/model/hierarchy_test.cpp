// Hierarchy: level sizes, list invariants, small objects, translation, flat variant.
#include "engine/model/hierarchy.h"

#include <gtest/gtest.h>

#include <set>
#include <string>

#include "engine/core/error.h"
#include "engine/core/threads.h"
#include "tests/geometry/reference_neighbors.h"
#include "tests/model/model_test_util.h"

namespace dynscope {
namespace {

using testing::make_scene;

HierarchyOptions small_options() { return testing::small_hierarchy_options(); }

// Every valid entry indexes the source and respects the object rule; masked entries are −1.
void check_list(const NeighborList& nb, const HierarchyLevel& query, const HierarchyLevel& source,
                bool same_object) {
  ASSERT_EQ(nb.rows(), query.points.rows());
  for (Eigen::Index i = 0; i < nb.rows(); ++i) {
    for (Eigen::Index j = 0; j < nb.k(); ++j) {
      if (!nb.mask(i, j)) {
        EXPECT_EQ(nb.index(i, j), -1);
        continue;
      }
      const int32_t s = nb.index(i, j);
      ASSERT_GE(s, 0);
      ASSERT_LT(s, source.points.rows());
      EXPECT_EQ(source.object_ids[s] == query.object_ids[i], same_object);
    }
  }
}

TEST(HierarchyTest, LevelsShrinkAndListsAreConsistent) {
  const auto scene = make_scene(3, 120, 1);
  const HierarchyOptions o = small_options();
  const Hierarchy h = build_hierarchy(scene.points, scene.ids, o);
  ASSERT_EQ(h.num_levels(), 3);
  EXPECT_EQ(h.levels[0].points.rows(), 360);
  EXPECT_DOUBLE_EQ(h.levels[1].voxel, 0.08);
  EXPECT_DOUBLE_EQ(h.levels[2].voxel, 0.12);
  EXPECT_DOUBLE_EQ(h.levels[2].radius, 0.225);
  for (int l = 1; l < 3; ++l) {
    const HierarchyLevel& lv = h.levels[l];
    const HierarchyLevel& prev = h.levels[l - 1];
    EXPECT_LT(lv.points.rows(), prev.points.rows());
    ASSERT_EQ(lv.kept.size(), static_cast<size_t>(lv.points.rows()));
    // Every object survives downsampling.
    EXPECT_EQ(std::set<int32_t>(lv.object_ids.begin(), lv.object_ids.end()).size(), 3u);
    for (Eigen::Index i = 0; i < lv.points.rows(); ++i) {
      EXPECT_EQ(lv.points.row(i), prev.points.row(lv.kept[i]));
      // A kept point's nearest source in the level below is itself.
      EXPECT_EQ(lv.down.index(i, 0), lv.kept[i]);
    }
    check_list(lv.down, lv, prev, true);
    check_list(lv.up, prev, lv, true);
  }
  for (const HierarchyLevel& lv : h.levels) {
    check_list(lv.same, lv, lv, true);
    check_list(lv.relational, lv, lv, false);
    int with_relations = 0;
    for (Eigen::Index i = 0; i < lv.relational.rows(); ++i) {
      for (Eigen::Index j = 0; j < lv.relational.k(); ++j) {
        if (!lv.relational.mask(i, j)) continue;
        EXPECT_LE((lv.points.row(i) - lv.points.row(lv.relational.index(i, j))).norm(),
                  lv.radius + 1e-12);
      }
      with_relations += lv.relational.valid_count(i) > 0;
    }
    EXPECT_GT(with_relations, 0);
  }
}

void expect_same_list(const NeighborList& actual, const NeighborList& expected,
                      const std::string& what) {
  EXPECT_EQ(actual.index, expected.index) << what;
  EXPECT_EQ(actual.mask, expected.mask) << what;
}

// Every list of every level equals brute force over the levels' points, for the paper's model
// (same-object and relational lists) and for the flat baseline (plain kNN). The down and same
// lists of the coarser levels are taken from the searched lists (build_hierarchy), so this also
// checks those identities.
TEST(HierarchyTest, EveryListEqualsBruteForceOverItsLevels) {
  using reference::brute_force_knn;
  using reference::Relation;
  const auto scene = make_scene(4, 150, 6);
  for (const bool object_centric : {true, false}) {
    HierarchyOptions o = small_options();
    o.object_centric = object_centric;
    const Relation relation = object_centric ? Relation::kSameObject : Relation::kAll;
    const Hierarchy h = build_hierarchy(scene.points, scene.ids, o);
    for (int l = 0; l < h.num_levels(); ++l) {
      const HierarchyLevel& lv = h.levels[l];
      const std::string what =
          std::string(object_centric ? "object-centric" : "flat") + " level " + std::to_string(l);
      expect_same_list(
          lv.same,
          brute_force_knn(lv.points, lv.object_ids, lv.points, lv.object_ids, o.k, relation),
          what + " same");
      if (object_centric) {
        expect_same_list(lv.relational,
                         brute_force_knn(lv.points, lv.object_ids, lv.points, lv.object_ids,
                                         o.k_relational, Relation::kOtherObject, lv.radius),
                         what + " relational");
      }
      if (l == 0) continue;
      const HierarchyLevel& prev = h.levels[l - 1];
      expect_same_list(
          lv.down,
          brute_force_knn(lv.points, lv.object_ids, prev.points, prev.object_ids, o.k, relation),
          what + " down");
      expect_same_list(
          lv.up,
          brute_force_knn(prev.points, prev.object_ids, lv.points, lv.object_ids, o.k, relation),
          what + " up");
    }
  }
}

TEST(HierarchyTest, DoesNotDependOnTheThreadCount) {
  const auto scene = make_scene(3, 400, 7);
  for (const bool object_centric : {true, false}) {
    HierarchyOptions o = small_options();
    o.object_centric = object_centric;
    const int saved = compute_threads();
    set_compute_threads(1);
    const Hierarchy a = build_hierarchy(scene.points, scene.ids, o);
    set_compute_threads(2);
    const Hierarchy b = build_hierarchy(scene.points, scene.ids, o);
    set_compute_threads(saved);
    for (int l = 0; l < a.num_levels(); ++l) {
      const std::string what = "level " + std::to_string(l);
      EXPECT_EQ(a.levels[l].kept, b.levels[l].kept) << what;
      expect_same_list(a.levels[l].same, b.levels[l].same, what + " same");
      expect_same_list(a.levels[l].relational, b.levels[l].relational, what + " relational");
      expect_same_list(a.levels[l].down, b.levels[l].down, what + " down");
      expect_same_list(a.levels[l].up, b.levels[l].up, what + " up");
    }
  }
}

// An error part-way up the chain, with level 0's relational list already running beside it on
// two threads, reaches the caller as the same error as on one: level 0 accepts a point at 1e17
// (its trees take coordinates up to 1e18), level 1's voxel grid cannot index it.
TEST(HierarchyTest, AnErrorPartWayUpReachesTheCallerOnAnyThreadCount) {
  auto scene = make_scene(3, 400, 9);
  scene.points(700, 0) = 1e17;
  const int saved = compute_threads();
  for (const int threads : {1, 2}) {
    set_compute_threads(threads);
    try {
      build_hierarchy(scene.points, scene.ids, small_options());
      ADD_FAILURE() << "no error on " << threads << " threads";
    } catch (const ValueError& e) {
      EXPECT_NE(std::string(e.what()).find("too far from the origin"), std::string::npos)
          << e.what();
    }
  }
  set_compute_threads(saved);
}

TEST(HierarchyTest, ObjectWithFewerThanKPointsIsMaskedNotPadded) {
  auto scene = make_scene(2, 60, 2);
  // A third object with 3 points.
  scene.points.conservativeResize(123, 3);
  scene.points.bottomRows(3) << 0.7, 0.0, 0.1, 0.72, 0.01, 0.1, 0.71, 0.03, 0.12;
  scene.ids.insert(scene.ids.end(), {99, 99, 99});
  const Hierarchy h = build_hierarchy(scene.points, scene.ids, small_options());
  const HierarchyLevel& l0 = h.levels[0];
  for (Eigen::Index i = 120; i < 123; ++i) {
    EXPECT_EQ(l0.same.valid_count(i), 3);
    EXPECT_EQ(l0.same.index(i, 3), -1);
  }
}

TEST(HierarchyTest, TranslationInXYSelectsTheSamePoints) {
  const auto scene = make_scene(3, 100, 3);
  Points moved = scene.points;
  moved.col(0).array() += 1.37;
  moved.col(1).array() -= 2.91;
  const Hierarchy a = build_hierarchy(scene.points, scene.ids, small_options());
  const Hierarchy b = build_hierarchy(moved, scene.ids, small_options());
  for (int l = 1; l < 3; ++l) {
    EXPECT_EQ(a.levels[l].kept, b.levels[l].kept) << "level " << l;
    EXPECT_EQ(a.levels[l].down.index, b.levels[l].down.index);
    EXPECT_EQ(a.levels[l].relational.index, b.levels[l].relational.index);
  }
}

TEST(HierarchyTest, FlatVariantUsesPlainKnnWithoutRelationalLists) {
  const auto scene = make_scene(3, 80, 4);
  HierarchyOptions o = small_options();
  o.object_centric = false;
  const Hierarchy h = build_hierarchy(scene.points, scene.ids, o);
  bool crosses_objects = false;
  for (const HierarchyLevel& lv : h.levels) {
    EXPECT_EQ(lv.relational.rows(), 0);
    for (Eigen::Index i = 0; i < lv.same.rows(); ++i) {
      EXPECT_EQ(lv.same.valid_count(i), 8);
      for (Eigen::Index j = 0; j < 8; ++j) {
        crosses_objects |= lv.object_ids[lv.same.index(i, j)] != lv.object_ids[i];
      }
    }
  }
  EXPECT_TRUE(crosses_objects);
}

// A model with relational units at level 0 only gets its relational list there and no other;
// every other list is the full hierarchy's.
TEST(HierarchyTest, RelationalTopOnlyBuildsLevelZerosRelationalListAlone) {
  const auto scene = make_scene(3, 80, 7);
  HierarchyOptions o = small_options();
  const Hierarchy full = build_hierarchy(scene.points, scene.ids, o);
  o.relational_top_only = true;
  const Hierarchy top = build_hierarchy(scene.points, scene.ids, o);
  ASSERT_EQ(top.num_levels(), full.num_levels());
  EXPECT_GT(top.levels[0].relational.rows(), 0);
  EXPECT_EQ(top.levels[0].relational.index, full.levels[0].relational.index);
  for (int l = 0; l < top.num_levels(); ++l) {
    const HierarchyLevel& a = top.levels[static_cast<size_t>(l)];
    const HierarchyLevel& b = full.levels[static_cast<size_t>(l)];
    if (l > 0) {
      EXPECT_GT(b.relational.rows(), 0);
      EXPECT_EQ(a.relational.rows(), 0) << "level " << l;
    }
    EXPECT_EQ(a.points, b.points);
    EXPECT_EQ(a.same.index, b.same.index);
    EXPECT_EQ(a.down.index, b.down.index);
    EXPECT_EQ(a.up.index, b.up.index);
  }
}

// The hierarchy builds a point relational list exactly at the levels where the model configured
// from the same options has a relational unit fed by points (one rule for both), for every kind,
// input and relational_top_only.
TEST(HierarchyTest, RelationalListsAreWhereTheModelRelatesPoints) {
  const auto scene = make_scene(3, 80, 11);
  for (ModelKind kind : {ModelKind::kPointConv, ModelKind::kGnn, ModelKind::kFlat}) {
    for (InputMode input : {InputMode::kPoints, InputMode::kMesh}) {
      for (bool top_only : {false, true}) {
        ModelConfig c = ModelConfig::preset("physion");
        c.kind = kind;
        c.input = input;
        c.relational_top_only = top_only;
        c.levels = 3;
        c.voxel = 0.08;
        const HierarchyOptions o = HierarchyOptions::from_config(c);
        const std::string what =
            to_string(kind) + " " + to_string(input) + (top_only ? " top only" : "");
        for (int l = 0; l < c.levels; ++l) {
          EXPECT_EQ(o.point_relational_at(l), c.has_relational(l) && input == InputMode::kPoints)
              << what << ", level " << l;
        }
        if (input == InputMode::kMesh) continue;  // mesh input needs faces to build
        const Hierarchy h = build_hierarchy(scene.points, scene.ids, o);
        for (int l = 0; l < h.num_levels(); ++l) {
          EXPECT_EQ(h.levels[static_cast<size_t>(l)].relational.rows() > 0,
                    o.point_relational_at(l))
              << what << ", level " << l;
        }
      }
    }
  }
}

TEST(HierarchyTest, RejectsBadInput) {
  const auto scene = make_scene(1, 10, 5);
  std::vector<int32_t> short_ids(scene.ids.begin(), scene.ids.end() - 1);
  EXPECT_THROW(build_hierarchy(scene.points, short_ids, small_options()), ValueError);
  HierarchyOptions o = small_options();
  o.levels = 0;
  EXPECT_THROW(build_hierarchy(scene.points, scene.ids, o), ValueError);
  EXPECT_THROW(build_hierarchy(Points(0, 3), {}, small_options()), ValueError);
}

}  // namespace
}  // namespace dynscope
