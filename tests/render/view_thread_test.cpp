// Tests of ViewThread: the image it draws equals the Renderer's on this thread, unchanged views are
// not redrawn, the newest request wins, failures come back once, and it stops with work queued.
#include "render/view_thread.h"

#include <gtest/gtest.h>

#include <vector>

#include "engine/core/error.h"
#include "render_test_util.h"

namespace dynscope::render {
namespace {

constexpr int kW = 200;
constexpr int kH = 150;

// Five frames of 400 points on a ring moving along x, coloured by a scalar, plus a mesh.
struct Fixture {
  std::shared_ptr<PointSeries> series;
  std::shared_ptr<MeshGeometry> box = make_mesh_geometry(make_box_mesh(Vec3(0.3, 0.3, 0.3)));

  Fixture() {
    std::vector<Points> frames;
    for (int f = 0; f < 5; ++f) {
      Points p(400, 3);
      for (int i = 0; i < 400; ++i) {
        const double a = 2.0 * M_PI * i / 400.0;
        p.row(i) << 0.6 * std::cos(a) + 0.1 * f, 0.6 * std::sin(a), 0.3 + 0.05 * (i % 7);
      }
      frames.push_back(p);
    }
    series = make_point_series(frames);
    for (int f = 0; f < 5; ++f) {
      for (int i = 0; i < 400; ++i) series->scalars.push_back(static_cast<float>(i % 50) / 50.0f);
    }
  }

  ViewRequest request(int frame) const {
    RenderScene scene;
    PointLayer layer;
    layer.name = "ring";
    layer.series = series;
    layer.frame = frame;
    layer.coloring = PointColoring::kScalar;
    layer.radius = 0.03f;
    scene.points.push_back(layer);
    MeshInstance mesh;
    mesh.name = "box";
    mesh.geometry = box;
    mesh.model = pose_matrix(Pose{Vec3(0.0, 0.0, 0.15), Quat::Identity()});
    scene.meshes.push_back(mesh);
    Camera camera;
    camera.distance = 3.0;
    ViewRequest r;
    r.width = kW;
    r.height = kH;
    // Two side-by-side views of the same scene, as the viewer's compare mode draws.
    r.items.push_back({scene, camera, Rect{0, 0, kW / 2, kH}});
    camera.yaw_deg += 60.0;
    r.items.push_back({scene, camera, Rect{kW / 2, 0, kW - kW / 2, kH}});
    return r;
  }
};

// What a Renderer on this thread draws for `r`.
Image draw_here(const ViewRequest& r) {
  GlContext& context = testing::osmesa(r.width, r.height);
  Renderer renderer(context);
  for (const ViewItem& item : r.items) renderer.render(item.scene, item.camera, item.rect);
  return context.read_pixels();
}

Image take_newest(ViewThread& thread, uint64_t number) {
  thread.wait(number);
  Image image;
  uint64_t drawn = 0;
  EXPECT_TRUE(thread.take(image, drawn));
  EXPECT_EQ(drawn, number);
  return image;
}

TEST(ViewThread, DrawsWhatTheRendererDrawsOnThisThread) {
  const Fixture fx;
  ViewThread thread;
  for (int frame : {0, 3}) {
    const uint64_t n = thread.submit(fx.request(frame));
    const Image image = take_newest(thread, n);
    ASSERT_EQ(image.width, kW);
    ASSERT_EQ(image.height, kH);
    const Image expected = draw_here(fx.request(frame));
    EXPECT_EQ(compare_images(image, expected, 0).max_difference, 0) << "frame " << frame;
  }
  // Different frames are different pictures (the test can tell them apart).
  EXPECT_LT(compare_images(draw_here(fx.request(0)), draw_here(fx.request(3)), 8).fraction_within,
            0.999);
}

TEST(ViewThread, AnUnchangedViewIsNotDrawnAgainAndFramesReuseTheUpload) {
  const Fixture fx;
  ViewThread thread;
  const uint64_t first = thread.submit(fx.request(1));
  take_newest(thread, first);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(thread.submit(fx.request(1)), first);
  thread.wait(first);
  EXPECT_EQ(thread.images_drawn(), 1);
  Image none;
  uint64_t number = 0;
  EXPECT_FALSE(thread.take(none, number));
  const int64_t uploads = thread.upload_count();
  EXPECT_EQ(uploads, 2);  // the ring series and the box mesh
  // Another frame, camera, rectangle or colour range is another image; the series stays uploaded.
  ViewRequest moved = fx.request(1);
  moved.items[0].camera.distance = 4.0;
  ViewRequest recoloured = fx.request(1);
  recoloured.items[1].scene.points[0].range_max = 2.0f;
  int64_t expected_images = 1;
  for (const ViewRequest& r : {fx.request(2), moved, recoloured}) {
    const uint64_t n = thread.submit(r);
    EXPECT_GT(n, first);
    take_newest(thread, n);
    EXPECT_EQ(thread.images_drawn(), ++expected_images);
  }
  EXPECT_EQ(thread.upload_count(), uploads);
}

TEST(ViewThread, TheNewestRequestWins) {
  const Fixture fx;
  ViewThread thread;
  uint64_t last = 0;
  for (int i = 0; i < 40; ++i) last = thread.submit(fx.request(i % 5));
  EXPECT_EQ(last, 40u);
  EXPECT_EQ(thread.submitted(), 40u);
  const Image image = take_newest(thread, last);
  EXPECT_EQ(compare_images(image, draw_here(fx.request(39 % 5)), 0).max_difference, 0);
  // Requests replaced while another was drawn were never drawn.
  EXPECT_LT(thread.images_drawn(), 40);
}

TEST(ViewThread, AFailedDrawIsReportedOnceAndTheThreadGoesOn) {
  const Fixture fx;
  ViewThread thread;
  ViewRequest bad = fx.request(0);
  bad.items[0].scene.points[0].frame = 9;  // the series has 5 frames
  const uint64_t n = thread.submit(bad);
  thread.wait(n);
  Image image;
  uint64_t number = 0;
  try {
    thread.take(image, number);
    FAIL() << "expected the drawing error";
  } catch (const ValueError& e) {
    EXPECT_NE(std::string(e.what()).find("'ring'"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(thread.take(image, number));
  const uint64_t good = thread.submit(fx.request(0));
  EXPECT_EQ(take_newest(thread, good).width, kW);
}

TEST(ViewThread, EmptyViewIsTheClearColourAndBadSizesAreRejected) {
  ViewThread thread;
  ViewRequest r;
  r.width = 8;
  r.height = 4;
  r.clear = Color(0.0f, 1.0f, 0.0f);
  const Image image = take_newest(thread, thread.submit(r));
  ASSERT_EQ(image.width, 8);
  EXPECT_EQ(image.pixel(3, 2)[0], 0);
  EXPECT_EQ(image.pixel(3, 2)[1], 255);
  r.width = 0;
  EXPECT_THROW(thread.submit(r), ValueError);
}

TEST(ViewThread, StopsWithRequestsQueuedAndWhileDrawing) {
  const Fixture fx;
  for (int round = 0; round < 5; ++round) {
    ViewThread thread;
    for (int i = 0; i < 3; ++i) thread.submit(fx.request(i));
  }  // destroyed while drawing or with a request pending: joins without hanging
  SUCCEED();
}

}  // namespace
}  // namespace dynscope::render
