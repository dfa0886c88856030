// Tests of Scene -> RenderScene and of the rollout comparison layers.
#include "render/scene_adapter.h"

#include <gtest/gtest.h>

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
