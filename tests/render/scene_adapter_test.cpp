// Tests of Scene -> RenderScene and of the rollout comparison layers.
#include "render/scene_adapter.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "engine/core/error.h"
#include "engine/model/hierarchy.h"
#include "engine/rollout/level_view.h"
#include "engine/rollout/model_points.h"
#include "render_test_util.h"

namespace dynscope::render {
namespace {

TEST(SceneAdapter, MeshesFollowPosesAndGridSitsOnTheFloor) {
  Scene scene = testing::shapes_scene(3);
  scene.trajectories[0].poses[2].position = Vec3(1.0, 2.0, 0.2);
  ViewSpec view;
  SceneRenderData data(scene, view);
  const RenderScene frame = data.frame(2, view);
  ASSERT_EQ(frame.meshes.size(), 3u);
  EXPECT_NEAR(frame.meshes[0].model(0, 3), 1.0f, 1e-6f);
  EXPECT_NEAR(frame.meshes[0].model(1, 3), 2.0f, 1e-6f);
  EXPECT_EQ(frame.meshes[0].opacity, 1.0f);
  // The same geometry object is shared by every frame (uploaded once).
  EXPECT_EQ(frame.meshes[0].geometry, data.frame(0, view).meshes[0].geometry);
  EXPECT_FLOAT_EQ(frame.grid.height, 0.0f);
  EXPECT_TRUE(frame.points.empty());
  EXPECT_THROW(data.frame(3, view), ValueError);
}

TEST(SceneAdapter, LevelViewsAreTheModelsOwnHierarchy) {
  const Scene scene = testing::shapes_scene(2);
  ViewSpec view;
  view.layers.ground_truth = true;
  view.layers.level_points = true;
  view.layers.neighborhoods = true;
  view.picked_point = 0;
  view.level = 2;
  ASSERT_TRUE(view_needs_levels(view));
  const std::shared_ptr<LevelViews> views = make_level_views(scene, view);
  const std::shared_ptr<const ModelTrace> at1 = views->at(1);
  EXPECT_EQ(views->at(1), at1) << "the last frame's view is kept";
  EXPECT_TRUE(is_level_view(*at1));

  // Reference: the model's own rule on the model's own points at frame 1 (Physion preset).
  const ModelConfig config = ModelConfig::preset("physion");
  EXPECT_EQ(views->config().to_json(), level_view_config(scene, view).to_json());
  const ModelPoints points = build_model_points(scene, SamplingOptions{});
  const Hierarchy h = build_model_hierarchy(points.positions(scene, 1), points.cloud.object_id,
                                            points.faces, config);
  ASSERT_EQ(at1->levels.size(), static_cast<size_t>(config.levels));
  for (int l = 0; l < h.num_levels(); ++l) {
    const HierarchyLevel& want = h.levels[static_cast<size_t>(l)];
    const TraceLevel& got = at1->levels[static_cast<size_t>(l)];
    EXPECT_EQ(got.points, want.points) << "level " << l;
    EXPECT_DOUBLE_EQ(got.voxel, want.voxel);
    EXPECT_DOUBLE_EQ(got.radius, want.radius);
    for (const TraceList& list : got.lists) {
      for (LevelList which : kLevelLists) {
        if (list.name != level_list_name(which)) continue;
        EXPECT_EQ(list.index, level_list(want, which).index) << l << "/" << list.name;
      }
    }
  }

  SceneRenderData level2(scene, view, at1);
  EXPECT_EQ(level2.level_size(), static_cast<int>(h.levels[2].points.rows()));
  EXPECT_LT(level2.level_size(), static_cast<int>(level2.cloud().size()));
  EXPECT_NEAR(level2.level_voxel(), config.voxel_at(2), 1e-12);
  EXPECT_NEAR(level2.level_radius(), h.levels[2].radius, 1e-12);
  const RenderScene frame = level2.frame(1, view);
  ASSERT_GE(frame.lines.size(), 1u);
  const LineSet& edges = frame.lines[0];
  ASSERT_GT(edges.positions.size(), 0u);
  const Points& p2 = h.levels[2].points;
  for (size_t s = 0; s < edges.positions.size(); s += 6) {
    EXPECT_NEAR(edges.positions[s], p2(0, 0), 1e-5);
    EXPECT_NEAR(edges.positions[s + 2], p2(0, 2), 1e-5);
  }
  // The neighbourhood is the model's list row: same-object kNN of K = config.k.
  const auto nb = level2.level_neighbors(1, 0);
  EXPECT_EQ(nb.same.index, h.levels[2].same.index.row(0));
  EXPECT_EQ(nb.relational.index, h.levels[2].relational.index.row(0));
  EXPECT_TRUE(nb.same_weight.empty()) << "a level view has no filter weights";
  EXPECT_FLOAT_EQ(frame.meshes[0].opacity, 0.3f);
  // Another frame: that frame's level view.
  level2.set_levels(views->at(0));
  EXPECT_NO_THROW(level2.frame(0, view));
  EXPECT_THROW(level2.frame(1, view), ValueError);
  view.picked_point = level2.level_size();
  EXPECT_THROW(level2.frame(0, view), ValueError);
}

TEST(SceneAdapter, WithoutALevelViewOnlyTheSampledPointsAreDrawn) {
  const Scene scene = testing::shapes_scene(2);
  ViewSpec view;
  view.layers.level_points = true;
  SceneRenderData level0(scene, view);
  EXPECT_EQ(level0.level_size(), static_cast<int>(level0.cloud().size()));
  EXPECT_FALSE(view_needs_levels(view));
  EXPECT_NO_THROW(level0.frame(1, view));
  EXPECT_DOUBLE_EQ(level0.level_radius(), 0.0);
  view.layers.neighborhoods = true;
  view.picked_point = 0;
  EXPECT_THROW(level0.frame(1, view), ValueError);
  EXPECT_THROW(level0.level_neighbors(1, 0), ValueError);
  view.picked_point = -1;
  view.layers.interaction_points = true;
  EXPECT_THROW(level0.frame(1, view), ValueError);
  view.layers.interaction_points = false;
  view.level = 1;
  EXPECT_THROW(SceneRenderData(scene, view), ValueError);
}

TEST(SceneAdapter, InteractionPointsComeFromAMeshInputLevelView) {
  const Scene scene = testing::shapes_scene(1);
  ViewSpec view;
  view.layers.interaction_points = true;
  view.layers.level_points = true;
  ASSERT_TRUE(view_needs_levels(view));
  EXPECT_EQ(level_view_config(scene, view).input, InputMode::kMesh);
  const std::shared_ptr<LevelViews> views = make_level_views(scene, view);
  const std::shared_ptr<const ModelTrace> t = views->at(0);
  ASSERT_TRUE(t->has_mesh);
  SceneRenderData data(scene, view, t);
  const RenderScene frame = data.frame(0, view);
  bool drawn = false;
  for (const PointLayer& p : frame.points) {
    if (p.name == "interaction points") drawn = p.series->num_points == t->mesh.points.rows();
  }
  EXPECT_EQ(drawn, t->mesh.points.rows() > 0);
  // A model that reads points has none: nothing drawn, and the legend says why.
  view.layers.interaction_points = false;
  const std::shared_ptr<const ModelTrace> points = make_level_views(scene, view)->at(0);
  view.layers.interaction_points = true;
  SceneRenderData point_data(scene, view, points);
  for (const PointLayer& p : point_data.frame(0, view).points) {
    EXPECT_NE(p.name, "interaction points");
  }
  bool said = false;
  for (const std::string& line : point_data.legend(view)) {
    said |= line.find("no interaction points") != std::string::npos;
  }
  EXPECT_TRUE(said);
}

TEST(SceneAdapter, VoxelBoxesHaveTheLevelVoxelSize) {
  const Scene scene = testing::shapes_scene(1);
  ViewSpec view;
  view.layers.voxels = true;
  view.level = 1;
  SceneRenderData data(scene, view, make_level_views(scene, view)->at(0));
  const RenderScene frame = data.frame(0, view);
  ASSERT_FALSE(frame.boxes.empty());
  for (const WireBox& b : frame.boxes) {
    EXPECT_NEAR(b.max.x() - b.min.x(), 0.075f, 1e-5f);
  }
}

// A two-level trace by hand: level 0 has 4 points (objects 0,0,0,1), level 1 keeps points 0 and 3.
ModelTrace two_level_trace(int frame) {
  ModelTrace t;
  t.frame = frame;
  TraceLevel l0;
  l0.points.resize(4, 3);
  l0.points << 0.1, 0.2, 0.0, 0.3, 0.2, 0.0, 0.1, 0.4, 0.0, 0.6, 0.2, 0.1;
  l0.object_ids = {0, 0, 0, 1};
  l0.radius = 0.5;
  TraceList same0{"same", 0, 0, IndexMatrix(4, 2), MaskMatrix(4, 2)};
  same0.index << 0, 1, 1, 0, 2, 0, 3, -1;
  same0.mask << 1, 1, 1, 1, 1, 1, 1, 0;
  l0.lists.push_back(same0);
  TraceList rel0{"relational", 0, 0, IndexMatrix(4, 1), MaskMatrix(4, 1)};
  rel0.index << 3, 3, -1, 1;
  rel0.mask << 1, 1, 0, 1;
  l0.lists.push_back(rel0);
  TraceLevel l1;
  l1.points.resize(2, 3);
  l1.points << 0.1, 0.2, 0.0, 0.6, 0.2, 0.1;
  l1.object_ids = {0, 1};
  l1.kept = {0, 3};
  l1.voxel = 0.3;
  l1.radius = 0.75;
  TraceList down{"down", 1, 0, IndexMatrix(2, 3), MaskMatrix(2, 3)};
  down.index << 0, 1, 2, 3, -1, -1;
  down.mask << 1, 1, 1, 1, 0, 0;
  l1.lists.push_back(down);
  TraceList up{"up", 0, 1, IndexMatrix(4, 1), MaskMatrix(4, 1)};
  up.index << 0, 0, 0, 1;
  up.mask << 1, 1, 1, 1;
  l1.lists.push_back(up);
  t.levels = {l0, l1};
  TraceQuery q;
  q.point = 0;
  q.conv = "unet.stem.0.object.conv";
  q.level = 0;
  q.list = "0/same";
  q.query_index = 0;
  q.neighbors = {0, 1};
  q.mask = {1, 1};
  q.weights.resize(2, 2);
  q.weights << 3.0, 4.0, 0.0, 1.0;
  t.queries.push_back(q);
  return t;
}

TEST(SceneAdapter, TraceGivesTheModelsLevelsListsAndFilterWeights) {
  const Scene scene = testing::shapes_scene(3);
  const auto trace = std::make_shared<const ModelTrace>(two_level_trace(1));
  ViewSpec view;
  view.layers.level_points = true;
  view.layers.neighborhoods = true;
  view.picked_point = 0;
  SceneRenderData level0(scene, view, trace);
  EXPECT_EQ(level0.level_size(), 4);
  const auto nb = level0.level_neighbors(1, 0);
  ASSERT_EQ(nb.same.k(), 2);
  EXPECT_EQ(nb.same.index(0, 1), 1);
  ASSERT_EQ(nb.relational.k(), 1);
  EXPECT_EQ(nb.relational.index(0, 0), 3);
  ASSERT_EQ(nb.same_weight.size(), 2u);
  EXPECT_DOUBLE_EQ(nb.same_weight[0], 5.0);
  EXPECT_DOUBLE_EQ(nb.same_weight[1], 1.0);
  EXPECT_EQ(nb.same_conv, "unet.stem.0.object.conv");
  EXPECT_TRUE(nb.relational_weight.empty());
  EXPECT_DOUBLE_EQ(level0.level_radius(), 0.5);
  // The trace holds one frame: level layers elsewhere are a clear error, plain frames are fine.
  EXPECT_NO_THROW(level0.frame(1, view));
  EXPECT_THROW(level0.frame(2, view), ValueError);
  ViewSpec plain;
  EXPECT_NO_THROW(level0.frame(2, plain));
  // The neighbour points carry ‖h‖ as scalars for the colormap.
  const RenderScene frame = level0.frame(1, view);
  bool coloured = false;
  for (const PointLayer& p : frame.points) {
    if (p.name == "object neighbours") {
      coloured = p.coloring == PointColoring::kScalar && p.series->scalars.size() == 1u &&
                 p.series->scalars[0] == 1.0f;
    }
  }
  EXPECT_TRUE(coloured);

  view.level = 1;
  view.layers.voxels = true;
  SceneRenderData level1(scene, view, trace);
  EXPECT_EQ(level1.level_size(), 2);
  EXPECT_DOUBLE_EQ(level1.level_voxel(), 0.3);
  const auto nb1 = level1.level_neighbors(1, 0);
  EXPECT_EQ(nb1.sources, (std::vector<int32_t>{0, 1, 2}));
  EXPECT_EQ(nb1.feeds, (std::vector<int32_t>{0, 1, 2}));
  EXPECT_EQ(level1.level_neighbors(1, 1).feeds, (std::vector<int32_t>{3}));
  // Voxel boxes sit on the model's grid, anchored at (min x, min y, 0) of the level-0 points.
  const RenderScene f1 = level1.frame(1, view);
  ASSERT_EQ(f1.boxes.size(), 2u);
  for (const WireBox& b : f1.boxes) {
    const float r = std::fmod(b.min.x() - 0.1f + 3.0f, 0.3f);
    EXPECT_LT(std::min(r, 0.3f - r), 1e-5f) << "box at x = " << b.min.x();
    EXPECT_NEAR(b.max.x() - b.min.x(), 0.3f, 1e-5f);
  }
  EXPECT_EQ(trace_level0_point(*trace, 1, 1), 3);
  EXPECT_THROW(trace_level0_point(*trace, 2, 0), ValueError);
  view.level = 2;
  EXPECT_THROW(SceneRenderData(scene, view, trace), ValueError);
}

TEST(SceneAdapter, MeshTraceDrawsTheModelsInteractionPairsAndFaces) {
  const Scene scene = testing::shapes_scene(3);
  ModelTrace t = two_level_trace(1);
  t.has_mesh = true;
  t.mesh.faces.resize(2, 3);
  t.mesh.faces << 0, 1, 2, 3, 2, 1;
  t.mesh.points.resize(2, 3);
  t.mesh.points << 0.2, 0.3, 0.0, 0.5, 0.3, 0.05;
  t.mesh.face = {0, 1};
  t.mesh.object_ids = {0, 1};
  TraceList senders{"senders", -1, -1, IndexMatrix(2, 1), MaskMatrix(2, 1)};
  senders.index << 1, -1;  // point 1 sends to point 0
  senders.mask << 1, 0;
  t.mesh.lists.push_back(senders);
  ViewSpec view;
  view.layers.interaction_points = true;
  SceneRenderData data(scene, view, std::make_shared<const ModelTrace>(t));
  const RenderScene frame = data.frame(1, view);
  const LineSet* pairs = nullptr;
  const LineSet* faces = nullptr;
  for (const LineSet& l : frame.lines) {
    if (l.name == "interaction pairs") pairs = &l;
    if (l.name == "interaction faces") faces = &l;
  }
  ASSERT_NE(pairs, nullptr);
  ASSERT_NE(faces, nullptr);
  ASSERT_EQ(pairs->positions.size(), 6u) << "one sender -> receiver segment";
  EXPECT_NEAR(pairs->positions[0], 0.5f, 1e-6f);  // from the sender
  EXPECT_NEAR(pairs->positions[3], 0.2f, 1e-6f);  // to the receiver
  EXPECT_EQ(faces->positions.size(), 2u * 3u * 6u) << "both faces outlined";
  EXPECT_THROW(data.frame(2, view), ValueError) << "the trace holds frame 1 only";
}

TEST(SceneAdapter, ComparisonCarriesPerPointErrors) {
  Points truth(2, 3), pred(2, 3);
  truth << 0, 0, 0, 1, 0, 0;
  pred << 0, 0, 0.3, 1, 0.4, 0;
  const ComparisonSeries c = make_comparison_series({truth, truth}, {truth, pred}, {0, 1});
  ASSERT_EQ(c.prediction->scalars.size(), 4u);
  EXPECT_FLOAT_EQ(c.prediction->scalars[2], 0.3f);
  EXPECT_FLOAT_EQ(c.prediction->scalars[3], 0.4f);
  EXPECT_FLOAT_EQ(c.max_error, 0.4f);
  ViewSpec view;
  view.layers.error = true;
  view.layers.ghost = true;
  RenderScene out;
  add_comparison_layers(out, c, 1, view, 0.05f);
  ASSERT_EQ(out.points.size(), 2u);
  EXPECT_EQ(out.points[0].coloring, PointColoring::kScalar);
  EXPECT_FLOAT_EQ(out.points[0].range_max, 0.4f);
  EXPECT_EQ(out.points[1].series, c.truth);
  EXPECT_LT(out.points[1].opacity, 1.0f);
  EXPECT_NO_THROW(out.validate());
  EXPECT_THROW(make_comparison_series({truth}, {truth, pred}, {0, 1}), ValueError);
  EXPECT_THROW(make_comparison_series({truth}, {truth}, {0}), ValueError);
}

TEST(SceneAdapter, AttributionReplacesThePredictionColours) {
  Rollout r;
  r.dt_s = 0.1;
  r.observed_frames = 1;
  r.rest = Points::Zero(3, 3);
  r.object_ids = {1, 1, 2};
  Points p(3, 3);
  p << 0, 0, 0, 1, 0, 0, 2, 0, 0;
  r.predicted = {p, p};
  r.truth = {p, p};
  r.poses.resize(2);
  r.point_error = {0.0, 0.0};
  const RolloutRenderData data = make_rollout_render_data(r, nullptr);
  PointAttribution a;
  a.shares = {0.0f, 0.75f, 0.25f};
  a.explained = {0};
  const auto series = make_attribution_series(data, a);
  ASSERT_EQ(series->colors.size(), 9u);
  // No share: light grey; the largest share: the colormap's top; a smaller one in between.
  EXPECT_FLOAT_EQ(series->colors[0], series->colors[1]);
  EXPECT_FLOAT_EQ(series->colors[1], series->colors[2]);
  const Color top = colormap("turbo", 1.0f);
  EXPECT_FLOAT_EQ(series->colors[3], top.x());
  EXPECT_FLOAT_EQ(series->colors[5], top.z());
  const Color mid = colormap("turbo", 0.1f + 0.9f * std::sqrt(0.25f / 0.75f));
  EXPECT_FLOAT_EQ(series->colors[6], mid.x());
  EXPECT_EQ(series->positions, data.series.prediction->positions);

  ViewSpec view;
  view.layers.error = true;
  view.layers.ghost = true;
  RenderScene out = rollout_frame(data, 1, view);
  const size_t layers = out.points.size();
  add_attribution_layers(out, series, a, 1, 0.05f);
  ASSERT_EQ(out.points.size(), layers + 1) << "prediction replaced, a halo added";
  for (const PointLayer& l : out.points) EXPECT_NE(l.name, kPredictionLayer);
  const PointLayer& halo = out.points.back();
  ASSERT_EQ(halo.series->num_points, 1);
  EXPECT_FLOAT_EQ(halo.series->positions[0], 0.0f);
  EXPECT_LT(halo.opacity, 1.0f);
  EXPECT_NO_THROW(out.validate());

  a.shares = {0.5f, 0.5f};
  EXPECT_THROW(make_attribution_series(data, a), ValueError);
  a.shares = {0.0f, 0.5f, 0.5f};
  a.explained = {3};
  EXPECT_THROW(make_attribution_series(data, a), ValueError);
}

TEST(SceneAdapter, GridSpacingIsRound) {
  Aabb box;
  box.extend(Vec3(-2, -1, 0));
  box.extend(Vec3(2, 1, 1));
  const GroundGrid g = grid_for_bounds(box);
  EXPECT_FLOAT_EQ(g.extent, 5.0f);
  EXPECT_FLOAT_EQ(g.spacing, 0.5f);
  box.extend(Vec3(0, 0, -0.5));
  EXPECT_FLOAT_EQ(grid_for_bounds(box).height, -0.5f);
}

}  // namespace
}  // namespace dynscope::render
