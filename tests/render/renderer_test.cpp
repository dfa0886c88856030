// Tests of the renderer on OSMesa: orientation, frame offsets, buffer reuse, colormaps, picking.
#include "render/renderer.h"

#include <gtest/gtest.h>

#include <cmath>

#include "engine/core/error.h"
#include "render/scene_adapter.h"
#include "render_test_util.h"

namespace dynscope::render {
namespace {

// Centroid of pixels whose colour differs from the background by more than 60 in some channel.
Eigen::Vector2d centroid_of_non_background(const Image& image, const Color& background,
                                           int* count = nullptr) {
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  int n = 0;
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      const uint8_t* p = image.pixel(x, y);
      bool differs = false;
      for (int c = 0; c < 3; ++c) differs |= std::abs(p[c] - background[c] * 255.0f) > 60.0f;
      if (differs) {
        sum += Eigen::Vector2d(x + 0.5, y + 0.5);
        ++n;
      }
    }
  }
  if (count) *count = n;
  return n ? Eigen::Vector2d(sum / n) : Eigen::Vector2d(-1, -1);
}

RenderScene moving_point_scene(const std::shared_ptr<PointSeries>& series, int frame) {
  RenderScene scene;
  scene.grid.visible = false;
  PointLayer layer;
  layer.series = series;
  layer.frame = frame;
  layer.color = Color(0.9f, 0.1f, 0.1f);
  layer.radius = 0.1f;
  scene.points.push_back(layer);
  return scene;
}

TEST(Renderer, ZIsUpOnScreen) {
  GlContext& context = testing::osmesa(160, 120);
  Renderer renderer(context, 0);
  RenderScene scene;
  scene.grid.visible = false;
  MeshInstance box;
  box.geometry = make_mesh_geometry(make_box_mesh(Vec3(0.3, 0.3, 0.3)));
  box.model = pose_matrix(Pose{Vec3(0, 0, 0.6), Quat::Identity()});
  box.color = Color(0.1f, 0.1f, 0.9f);
  scene.meshes.push_back(box);
  Camera camera;
  camera.set_preset(ViewPreset::kFront);
  camera.distance = 4;
  const Image image = renderer.render_image(scene, camera);
  int n = 0;
  const Eigen::Vector2d c = centroid_of_non_background(image, scene.background, &n);
  ASSERT_GT(n, 50);
  const Vec3 expected = camera.project(Vec3(0, 0, 0.6), 160, 120);
  EXPECT_LT(c.y(), 60.0);  // above the image centre
  EXPECT_NEAR(c.x(), expected.x(), 1.5);
  EXPECT_NEAR(c.y(), expected.y(), 1.5);
}

TEST(Renderer, FramesAreDrawnByOffsetWithoutReupload) {
  GlContext& context = testing::osmesa(160, 120);
  Renderer renderer(context, 0);
  std::vector<Points> frames;
  for (int f = 0; f < 5; ++f) {
    Points p(1, 3);
    p << -0.8 + 0.4 * f, 0.0, 0.0;
    frames.push_back(p);
  }
  auto series = make_point_series(frames);
  Camera camera;
  camera.set_preset(ViewPreset::kFront);
  camera.distance = 5;
  for (int f = 0; f < 5; ++f) {
    const RenderScene scene = moving_point_scene(series, f);
    const Image image = renderer.render_image(scene, camera);
    const Eigen::Vector2d c = centroid_of_non_background(image, scene.background);
    const Vec3 expected = camera.project(series->position(f, 0), 160, 120);
    EXPECT_NEAR(c.x(), expected.x(), 1.0) << "frame " << f;
    EXPECT_NEAR(c.y(), expected.y(), 1.0) << "frame " << f;
  }
  EXPECT_EQ(renderer.upload_count(), 1);
  // A different series is a new upload; the old one is evicted once released.
  auto other = make_point_series(frames);
  renderer.render(moving_point_scene(other, 0), camera);
  EXPECT_EQ(renderer.upload_count(), 2);
  series.reset();
  renderer.render(moving_point_scene(other, 1), camera);
  EXPECT_EQ(renderer.cached_buffers(), 1u);
}

TEST(Renderer, ScalarColouringUsesTheColormapRange) {
  GlContext& context = testing::osmesa(64, 64);
  Renderer renderer(context, 0);
  Points p(1, 3);
  p << 0, 0, 0;
  auto series = make_point_series({p});
  series->scalars = {5.0f};
  RenderScene scene = moving_point_scene(series, 0);
  scene.points[0].coloring = PointColoring::kScalar;
  scene.points[0].colormap = "turbo";
  scene.points[0].range_min = 0.0f;
  scene.points[0].range_max = 5.0f;
  scene.points[0].radius = 0.4f;
  Camera camera;
  camera.distance = 3;
  Image image = renderer.render_image(scene, camera);
  const uint8_t* top = image.pixel(32, 32);
  EXPECT_GT(top[0], 2 * top[2]);  // turbo's high end is red
  scene.points[0].range_max = 100.0f;
  image = renderer.render_image(scene, camera);
  const uint8_t* low = image.pixel(32, 32);
  EXPECT_GT(low[2], low[0]);  // near the low end: blue
  EXPECT_EQ(renderer.upload_count(), 1);
}

TEST(Renderer, PickFindsThePointUnderThePixelAndRespectsOcclusion) {
  GlContext& context = testing::osmesa(200, 150);
  Renderer renderer(context, 4);
  Points p(3, 3);
  p << -1.0, 0.0, 0.0, 0.0, 0.0, 0.5, 1.0, 0.0, 0.0;
  RenderScene scene;
  PointLayer decoy;
  decoy.series = make_point_series({Points(Points::Zero(1, 3))});
  decoy.pickable = false;
  scene.points.push_back(decoy);
  PointLayer layer;
  layer.series = make_point_series({p});
  layer.radius = 0.15f;
  scene.points.push_back(layer);
  Camera camera;
  camera.set_preset(ViewPreset::kFront);
  camera.distance = 6;
  for (int i = 0; i < 3; ++i) {
    const Vec3 px = camera.project(p.row(i).transpose(), 200, 150);
    const PickResult r =
        renderer.pick(scene, camera, static_cast<int>(px.x()), static_cast<int>(px.y()));
    EXPECT_EQ(r.layer, 1) << i;
    EXPECT_EQ(r.point, i);
  }
  EXPECT_FALSE(renderer.pick(scene, camera, 2, 2).hit());
  EXPECT_FALSE(renderer.pick(scene, camera, -1, 5).hit());
  // A box in front of point 2 hides it from picking.
  MeshInstance wall;
  wall.geometry = make_mesh_geometry(make_box_mesh(Vec3(0.6, 0.1, 0.6)));
  wall.model = pose_matrix(Pose{Vec3(1.0, -1.0, 0.0), Quat::Identity()});
  scene.meshes.push_back(wall);
  const Vec3 px = camera.project(p.row(2).transpose(), 200, 150);
  EXPECT_FALSE(
      renderer.pick(scene, camera, static_cast<int>(px.x()), static_cast<int>(px.y())).hit());
}

TEST(Renderer, InconsistentSceneIsAValueError) {
  GlContext& context = testing::osmesa(32, 32);
  Renderer renderer(context, 0);
  RenderScene scene;
  PointLayer layer;
  layer.name = "bad";
  layer.series = make_point_series({Points(Points::Zero(2, 3))});
  layer.frame = 3;
  scene.points.push_back(layer);
  try {
    renderer.render(scene, Camera{});
    FAIL();
  } catch (const ValueError& e) {
    EXPECT_NE(std::string(e.what()).find("'bad'"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace dynscope::render

namespace dynscope::render {
namespace {

// A disc covers about the area of the sphere's silhouette at the same place, and picks the same
// point; the style auto-switches above kDiscPointThreshold points.
TEST(Renderer, DiscsCoverTheSphereSilhouetteAndPick) {
  GlContext& context = testing::osmesa(160, 120);
  Renderer renderer(context, 0);
  Points p(1, 3);
  p.row(0) = Eigen::RowVector3d(0.2, 0.0, 0.5);
  const auto series = make_point_series({p});
  Camera camera;
  camera.set_preset(ViewPreset::kFront);
  camera.distance = 4;
  RenderScene scene = moving_point_scene(series, 0);
  scene.point_style = PointStyle::kSpheres;
  int spheres = 0, discs = 0;
  const Eigen::Vector2d a =
      centroid_of_non_background(renderer.render_image(scene, camera), scene.background, &spheres);
  scene.point_style = PointStyle::kDiscs;
  const Eigen::Vector2d b =
      centroid_of_non_background(renderer.render_image(scene, camera), scene.background, &discs);
  ASSERT_GT(spheres, 20);
  EXPECT_NEAR(discs, spheres, 0.25 * spheres);
  EXPECT_LT((a - b).norm(), 1.5);
  const PickResult hit =
      renderer.pick(scene, camera, static_cast<int>(b.x()), static_cast<int>(b.y()));
  EXPECT_TRUE(hit.hit());
  EXPECT_EQ(hit.point, 0);
  EXPECT_FALSE(renderer.pick(scene, camera, 2, 2).hit());
  EXPECT_EQ(scene.resolved_point_style(), PointStyle::kDiscs);
  scene.point_style = PointStyle::kAuto;
  EXPECT_EQ(scene.resolved_point_style(), PointStyle::kSpheres);
  scene.points[0].series = make_point_series({Points::Zero(kDiscPointThreshold + 1, 3)});
  EXPECT_EQ(scene.resolved_point_style(), PointStyle::kDiscs);
  EXPECT_EQ(parse_point_style("discs"), PointStyle::kDiscs);
  EXPECT_THROW(parse_point_style("cubes"), ValueError);
}

// Values are checked when a series is uploaded (once), sizes on every frame.
TEST(Renderer, NonFiniteSeriesIsRejectedAtUpload) {
  GlContext& context = testing::osmesa(64, 48);
  Renderer renderer(context, 0);
  Points p = Points::Zero(3, 3);
  p(1, 2) = std::nan("");
  const RenderScene scene = moving_point_scene(make_point_series({p}), 0);
  EXPECT_NO_THROW(scene.validate());  // O(1) per frame: sizes only
  EXPECT_THROW(renderer.render(scene, Camera()), ValueError);
}

// A viewport rectangle limits clearing and drawing to itself.
TEST(Renderer, ViewportRectLimitsTheImage) {
  GlContext& context = testing::osmesa(80, 40);
  Renderer renderer(context, 0);
  RenderScene red, blue;
  red.grid.visible = blue.grid.visible = false;
  red.background = Color(1.0f, 0.0f, 0.0f);
  blue.background = Color(0.0f, 0.0f, 1.0f);
  renderer.render(red, Camera(), Rect{0, 0, 40, 40});
  renderer.render(blue, Camera(), Rect{40, 0, 40, 40});
  const Image image = context.read_pixels();
  EXPECT_EQ(image.pixel(10, 20)[0], 255);
  EXPECT_EQ(image.pixel(10, 20)[2], 0);
  EXPECT_EQ(image.pixel(70, 20)[0], 0);
  EXPECT_EQ(image.pixel(70, 20)[2], 255);
  EXPECT_THROW(renderer.render(red, Camera(), Rect{60, 0, 40, 40}), ValueError);
  EXPECT_EQ(find_rect(45, 3, {Rect{0, 0, 40, 40}, Rect{40, 0, 40, 40}}), 1);
  EXPECT_EQ(find_rect(95, 3, {Rect{0, 0, 40, 40}}), -1);
}

}  // namespace
}  // namespace dynscope::render
