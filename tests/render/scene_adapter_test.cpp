// Tests of Scene -> RenderScene and of the rollout comparison layers.
#include "render/scene_adapter.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "engine/core/error.h"
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

TEST(SceneAdapter, LevelsHaveFewerPointsAndNeighbourhoodsStartAtThePickedPoint) {
  const Scene scene = testing::shapes_scene(2);
  ViewSpec view;
  view.layers.ground_truth = true;
  view.layers.level_points = true;
  view.layers.neighborhoods = true;
  view.picked_point = 0;
  view.neighbors = 8;
  SceneRenderData level0(scene, view);
  view.level = 2;
  SceneRenderData level2(scene, view);
  EXPECT_EQ(level0.level_indices().size(), static_cast<size_t>(level0.cloud().size()));
  EXPECT_LT(level2.level_indices().size(), level0.level_indices().size());
  EXPECT_GT(level2.level_indices().size(), 0u);
  EXPECT_NEAR(level2.level_voxel(), 0.05 * 2.25, 1e-12);

  const RenderScene frame = level2.frame(1, view);
  ASSERT_EQ(frame.lines.size(), 1u);
  const LineSet& edges = frame.lines[0];
  ASSERT_GT(edges.positions.size(), 0u);
  EXPECT_LE(edges.positions.size(), static_cast<size_t>(2 * 8 * 6));
  const int32_t picked = level2.level_indices()[0];
  const Points cloud1 = level2.cloud().positions(level2.scene(), 1);
  for (size_t s = 0; s < edges.positions.size(); s += 6) {
    EXPECT_NEAR(edges.positions[s], cloud1(picked, 0), 1e-5);
    EXPECT_NEAR(edges.positions[s + 2], cloud1(picked, 2), 1e-5);
  }
  EXPECT_FLOAT_EQ(frame.meshes[0].opacity, 0.3f);
  view.picked_point = static_cast<int>(level2.level_indices().size());
  EXPECT_THROW(level2.frame(0, view), ValueError);
}

TEST(SceneAdapter, VoxelBoxesHaveTheLevelVoxelSize) {
  const Scene scene = testing::shapes_scene(1);
  ViewSpec view;
  view.layers.voxels = true;
  view.level = 1;
  SceneRenderData data(scene, view);
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
  const auto nb = level0.level_neighbors(1, 0, 16);
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
  const auto nb1 = level1.level_neighbors(1, 0, 16);
  EXPECT_EQ(nb1.sources, (std::vector<int32_t>{0, 1, 2}));
  EXPECT_EQ(nb1.feeds, (std::vector<int32_t>{0, 1, 2}));
  EXPECT_EQ(level1.level_neighbors(1, 1, 16).feeds, (std::vector<int32_t>{3}));
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
