// Tests of the viewer's panel computations: point velocity, neighbourhoods, contacts, level counts.
#include "app/viewer/scene_inspection.h"

#include <gtest/gtest.h>

#include <set>

#include "engine/core/error.h"
#include "engine/model/model_config.h"
#include "engine/rollout/level_view.h"

namespace dynscope::app::viewer {
namespace {

// Box `id` of side 0.2 moving with `velocity` (units/s) from `start`, for `frames` frames.
void add_box(Scene& s, int32_t id, Role role, const Vec3& start, const Vec3& velocity, int frames) {
  Object o;
  o.id = id;
  o.name = "box_" + std::to_string(id);
  o.role = role;
  o.mesh = make_box_mesh(Vec3(0.2, 0.2, 0.2));
  s.objects.push_back(o);
  Trajectory t;
  for (int f = 0; f < frames; ++f) {
    t.poses.push_back(Pose{start + velocity * (f * s.dt_s), Quat::Identity()});
  }
  s.trajectories.push_back(t);
}

Scene two_boxes(int frames = 5) {
  Scene s;
  s.scenario = "collide";
  s.dt_s = 0.1;
  add_box(s, 0, Role::kTarget, Vec3(0, 0, 0.1), Vec3(1.0, 0.0, 0.0), frames);
  add_box(s, 1, Role::kZone, Vec3(1.0, 0, 0.1), Vec3::Zero(), frames);
  return s;
}

render::ViewSpec level_view(int level) {
  render::ViewSpec v;
  v.level = level;
  v.layers.level_points = true;
  return v;
}

// The scene's data at `level` with the model's level view of `frame`.
render::SceneRenderData with_levels(const Scene& s, int level, int frame) {
  const render::ViewSpec v = level_view(level);
  return render::SceneRenderData(s, v, render::make_level_views(s, v)->at(frame));
}

TEST(SceneInspection, VelocityIsTheFiniteDifferenceOfTheMotion) {
  const Scene s = two_boxes();
  const render::SceneRenderData data(s, level_view(0));
  for (int frame : {0, 2, 4}) {
    const PointInfo target = inspect_point(data, 0, frame);
    EXPECT_EQ(target.object_id, 0);
    EXPECT_EQ(target.object_name, "box_0");
    EXPECT_NEAR((target.velocity - Vec3(1, 0, 0)).norm(), 0.0, 1e-9) << "frame " << frame;
  }
  // The zone rests.
  int zone_point = -1;
  for (size_t i = 0; i < data.cloud().object_id.size(); ++i) {
    if (data.cloud().object_id[i] == 1) zone_point = static_cast<int>(i);
  }
  ASSERT_GE(zone_point, 0);
  EXPECT_NEAR(inspect_point(data, zone_point, 2).velocity.norm(), 0.0, 1e-12);
  EXPECT_THROW(inspect_point(data, -1, 0), ValueError);
  EXPECT_THROW(inspect_point(data, 0, 5), ValueError);
  // A level view's points are the sampled ones: the same velocity, at its frame only.
  const render::SceneRenderData levels = with_levels(s, 0, 2);
  const PointInfo viewed = inspect_point(levels, 0, 2);
  EXPECT_TRUE(viewed.has_velocity);
  EXPECT_NEAR((viewed.velocity - Vec3(1, 0, 0)).norm(), 0.0, 1e-9);
  EXPECT_THROW(inspect_point(levels, 0, 3), ValueError);
}

TEST(SceneInspection, PositionFollowsTheFrame) {
  const Scene s = two_boxes();
  const render::SceneRenderData data(s, level_view(0));
  const Points p0 = level_positions(data, 0), p3 = level_positions(data, 3);
  ASSERT_EQ(p0.rows(), static_cast<Eigen::Index>(data.cloud().size()));
  const PointInfo info = inspect_point(data, 0, 3);
  EXPECT_NEAR((info.position - p3.row(0).transpose()).norm(), 0.0, 1e-12);
  EXPECT_NEAR((p3.row(0) - p0.row(0)).x(), 0.3, 1e-9);  // 3 frames of 0.1 s at 1 unit/s
  // Level 1 of the model's hierarchy at frame 3: its points, one of them the model point it kept.
  const render::SceneRenderData level1 = with_levels(s, 1, 3);
  const Points q = level_positions(level1, 3);
  ASSERT_EQ(q.rows(), level1.level_size());
  ASSERT_LT(q.rows(), p3.rows());
  const PointInfo kept = inspect_point(level1, 0, 3);
  EXPECT_NEAR((kept.position - q.row(0).transpose()).norm(), 0.0, 1e-12);
  EXPECT_NEAR((p3.row(kept.cloud_point) - q.row(0)).norm(), 0.0, 1e-12);
  EXPECT_THROW(level_positions(level1, 2), ValueError);
}

TEST(SceneInspection, NeighbourhoodIsTheObjectKnnAndRelationalRadius) {
  const Scene s = two_boxes();
  // Frame 4: the target (x = 0.4) is 0.4 from the zone's centre, its faces 0.2 apart.
  const render::SceneRenderData data = with_levels(s, 0, 4);
  const Points p = level_positions(data, 4);
  const std::vector<int32_t> ids = data.cloud().object_id;
  // The target point closest to the zone.
  int picked = -1;
  for (Eigen::Index i = 0; i < p.rows(); ++i) {
    if (ids[i] == 0 && (picked < 0 || p(i, 0) > p(picked, 0))) picked = static_cast<int>(i);
  }
  const int k = ModelConfig::preset("physion").k;  // the model's K, not a viewer setting
  const Neighborhood n = point_neighborhood(data, picked, 4);
  EXPECT_EQ(n.k, k);
  EXPECT_DOUBLE_EQ(n.radius, ModelConfig::preset("physion").radius);
  EXPECT_DOUBLE_EQ(n.radius, data.level_radius());
  ASSERT_FALSE(n.object.empty());
  EXPECT_LE(static_cast<int>(n.object.size()), k);
  double farthest = 0.0;
  std::set<int> listed;
  for (const NeighborEntry& e : n.object) {
    EXPECT_NE(e.point, picked);
    EXPECT_EQ(e.object_id, 0);
    EXPECT_NEAR(e.distance, (p.row(e.point) - p.row(picked)).norm(), 1e-12);
    farthest = std::max(farthest, e.distance);
    listed.insert(e.point);
  }
  // kNN: nothing of the same object outside the list is strictly closer than the farthest listed.
  for (Eigen::Index i = 0; i < p.rows(); ++i) {
    if (ids[i] != 0 || i == picked || listed.count(static_cast<int>(i))) continue;
    EXPECT_GE((p.row(i) - p.row(picked)).norm(), farthest - 1e-12);
  }
  for (const NeighborEntry& e : n.relational) {
    EXPECT_EQ(e.object_id, 1);
    EXPECT_LE(e.distance, n.radius + 1e-12);
  }
  for (size_t i = 1; i < n.object.size(); ++i) {
    EXPECT_LE(n.object[i - 1].distance, n.object[i].distance);
  }
  EXPECT_THROW(point_neighborhood(data, picked, 3), ValueError) << "the view holds frame 4";
  const render::SceneRenderData plain(s, level_view(0));
  EXPECT_THROW(point_neighborhood(plain, picked, 4), ValueError) << "no level view";
}

TEST(SceneInspection, ContactDistanceTracksTheGap) {
  const Scene s = two_boxes();
  const render::SceneRenderData data(s, level_view(0));
  const std::vector<double> d = contact_distances(s, data.cloud());
  ASSERT_EQ(d.size(), 5u);
  // Faces are 0.8 - 0.1 f apart; points sit on the faces, within a voxel of their edges.
  for (int f = 0; f < 5; ++f) {
    const double gap = 0.8 - 0.1 * f;
    EXPECT_GE(d[f], gap - 1e-9) << f;
    EXPECT_LE(d[f], gap + data.voxel()) << f;
  }
  for (int f = 1; f < 5; ++f) EXPECT_LT(d[f], d[f - 1]);
  Scene no_roles = s;
  no_roles.objects[1].role = Role::kOther;
  EXPECT_TRUE(contact_distances(no_roles, data.cloud()).empty());
}

TEST(SceneInspection, LevelCountsShrinkAndSumPerObject) {
  const Scene s = two_boxes();
  const render::SceneRenderData data = with_levels(s, 0, 2);
  EXPECT_EQ(level_view_config(s).to_json(), ModelConfig::preset("physion").to_json());
  Scene movi = s;
  movi.scenario = "movi-a";
  EXPECT_EQ(level_view_config(movi).to_json(), ModelConfig::preset("kubric").to_json());
  const std::vector<LevelCount> counts = trace_level_counts(*data.trace());
  ASSERT_EQ(counts.size(), 4u);
  EXPECT_EQ(counts[0].points, static_cast<int>(data.cloud().size()));
  for (size_t l = 0; l < counts.size(); ++l) {
    int sum = 0;
    for (const auto& [id, c] : counts[l].per_object) sum += c;
    EXPECT_EQ(sum, counts[l].points);
    EXPECT_EQ(counts[l].per_object.size(), 2u);  // every object keeps a point at every level
    if (l > 0) {
      EXPECT_LE(counts[l].points, counts[l - 1].points);
      EXPECT_GT(counts[l].voxel, 0.0);
    }
  }
  EXPECT_THROW(render::make_level_views(s, level_view(0))->at(9), ValueError);
}

TEST(SceneInspection, NeighbourListsOfTwoInputsAreCompared) {
  auto trace = [](const std::vector<int32_t>& row0) {
    ModelTrace t;
    TraceLevel l;
    l.points = Points::Zero(4, 3);
    l.object_ids = {0, 0, 0, 0};
    TraceList same{"same", 0, 0, IndexMatrix(4, 3), MaskMatrix(4, 3)};
    same.index.setConstant(-1);
    same.mask.setZero();
    for (size_t k = 0; k < row0.size(); ++k) {
      same.index(0, static_cast<Eigen::Index>(k)) = row0[k];
      same.mask(0, static_cast<Eigen::Index>(k)) = 1;
    }
    l.lists.push_back(same);
    t.levels.push_back(l);
    return t;
  };
  const ModelTrace predicted = trace({0, 1, 2}), truth = trace({0, 2, 3});
  const ListDifference d = neighbor_difference(predicted, truth, LevelList::kSame, 0);
  EXPECT_EQ(d.only_a, (std::vector<int>{1})) << "the point itself is never a difference";
  EXPECT_EQ(d.only_b, (std::vector<int>{3}));
  const ListDifference none = neighbor_difference(predicted, truth, LevelList::kRelational, 0);
  EXPECT_TRUE(none.only_a.empty() && none.only_b.empty()) << "no relational list in either";
  EXPECT_TRUE(neighbor_difference(predicted, predicted, LevelList::kSame, 0).only_a.empty());
}

}  // namespace
}  // namespace dynscope::app::viewer
