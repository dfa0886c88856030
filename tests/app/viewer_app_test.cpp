// Tests of the viewer with the null platform: scrubbing, keys, playback, picking, view specs,
// errors.
#include "app/viewer/viewer_app.h"

#include <gtest/gtest.h>
#include <imgui.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "engine/core/error.h"
#include "engine/io/scene_file.h"
#include "render/image.h"
#include "render/png_io.h"
#include "render/renderer.h"
#include "render/view_spec.h"
#include "viewer_test_util.h"

namespace dynscope::app::viewer {
namespace {

namespace fs = std::filesystem;
using testing::HeadlessViewer;
using testing::kHeight;
using testing::kWidth;

fs::path temp_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("dynscope_viewer_test_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// The level point nearest the eye among those projecting into the free part of the window (not
// under the panels), with its pixel: nothing can hide it.
int visible_point(const ViewerApp& app, Vec3* pixel) {
  const Points p = level_positions(*app.state().active_data(), app.state().level_frame());
  int best = -1;
  for (Eigen::Index i = 0; i < p.rows(); ++i) {
    const Vec3 s = app.state().camera().project(p.row(i).transpose(), kWidth, kHeight);
    if (s.x() < 400 || s.x() > kWidth - 10 || s.y() < 10 || s.y() > kHeight - 80) continue;
    if (best < 0 || s.z() < pixel->z()) {
      best = static_cast<int>(i);
      *pixel = s;
    }
  }
  return best;
}

TEST(ViewerApp, ScrubbingShowsTheFramesDataWithoutUploads) {
  HeadlessViewer v;
  v.app.state().open_scene(testing::collide_scene());
  v.app.frame();
  const int64_t uploads = v.app.upload_count();
  const SceneDocument& doc = v.app.state().document();
  for (int k : {10, 25, 59}) {
    v.app.state().set_frame(k);
    v.app.frame();
    EXPECT_EQ(v.app.state().current_frame(), k);
    const PointInfo info = inspect_point(*doc.data, 3, v.app.state().current_frame());
    const Vec3 expected = doc.data->cloud().positions(doc.scene, k).row(info.cloud_point);
    EXPECT_NEAR((info.position - expected).norm(), 0.0, 1e-12) << "frame " << k;
  }
  // Point series and meshes are uploaded once; scrubbing changes only the frame drawn. (A picked
  // point's neighbourhood adds a few one-frame series per frame; none is shown here.)
  EXPECT_EQ(v.app.upload_count(), uploads);
  v.app.state().set_frame(1000);
  EXPECT_EQ(v.app.state().current_frame(), 59);
  v.app.state().set_frame(-4);
  EXPECT_EQ(v.app.state().current_frame(), 0);
}

TEST(ViewerApp, ScrubbedFrameIsWhatIsDrawn) {
  HeadlessViewer v;
  v.app.state().open_scene(testing::collide_scene());
  v.app.set_ui_visible(false);
  v.app.state().set_frame(0);
  v.app.frame();
  const render::Image first = v.app.read_pixels();
  v.app.state().set_frame(40);
  v.app.frame();
  const render::Image later = v.app.read_pixels();
  // The probe has moved: the images differ; going back reproduces frame 0 exactly.
  EXPECT_LT(render::compare_images(later, first, 8).fraction_within, 0.999);
  v.app.state().set_frame(0);
  v.app.frame();
  EXPECT_EQ(render::compare_images(v.app.read_pixels(), first, 0).max_difference, 0);
}

TEST(ViewerApp, KeyboardStepsAndPlays) {
  HeadlessViewer v;
  v.app.state().open_scene(testing::collide_scene());
  v.app.frame();
  v.platform.press_key(ImGuiKey_RightArrow);
  v.app.frame();
  v.app.frame();  // the key is released again: one step only
  EXPECT_EQ(v.app.state().current_frame(), 1);
  v.platform.press_key(ImGuiKey_End);
  v.app.frame();
  EXPECT_EQ(v.app.state().current_frame(), 59);
  v.platform.press_key(ImGuiKey_LeftArrow);
  v.app.frame();
  EXPECT_EQ(v.app.state().current_frame(), 58);
  v.platform.press_key(ImGuiKey_Home);
  v.app.frame();
  EXPECT_EQ(v.app.state().current_frame(), 0);
  // Space plays: 30 fps scene, 60 fps display, speed 1: one scene frame per two display frames.
  v.platform.press_key(ImGuiKey_Space);
  for (int i = 0; i < 20; ++i) v.app.frame();
  EXPECT_NEAR(v.app.state().current_frame(), 10, 1);
  v.platform.press_key(ImGuiKey_Space);
  v.app.frame();
  const int paused = v.app.state().current_frame();
  for (int i = 0; i < 10; ++i) v.app.frame();
  EXPECT_EQ(v.app.state().current_frame(), paused);
}

TEST(ViewerApp, ClickingAProjectedPointSelectsIt) {
  HeadlessViewer v;
  v.app.state().open_scene(testing::collide_scene());
  v.app.state().set_frame(12);
  v.app.frame();
  v.app.frame();
  Vec3 pixel;
  const int point = visible_point(v.app, &pixel);
  ASSERT_GE(point, 0);
  v.platform.move_mouse(static_cast<float>(pixel.x()), static_cast<float>(pixel.y()));
  v.app.frame();
  v.platform.set_button(0, true);
  v.app.frame();
  v.platform.set_button(0, false);
  v.app.frame();
  EXPECT_EQ(v.app.state().selected_point(), point);
  EXPECT_TRUE(v.app.state().layers().neighborhoods);
  // Same through pick() at another level: the index is the level's.
  v.app.state().set_level(1);
  EXPECT_EQ(v.app.state().selected_point(), -1);
  const int level_point = visible_point(v.app, &pixel);
  ASSERT_GE(level_point, 0);
  EXPECT_TRUE(v.app.pick(static_cast<int>(pixel.x()), static_cast<int>(pixel.y())));
  EXPECT_EQ(v.app.state().selected_point(), level_point);
  // Empty sky picks nothing and keeps the selection.
  EXPECT_FALSE(v.app.pick(kWidth - 2, 2));
  EXPECT_EQ(v.app.state().selected_point(), level_point);
}

TEST(ViewerApp, DraggingOrbitsInsteadOfPicking) {
  HeadlessViewer v;
  v.app.state().open_scene(testing::collide_scene());
  v.app.frame();
  const double yaw = v.app.state().camera().yaw_deg;
  v.platform.move_mouse(600, 300);
  v.app.frame();
  v.platform.set_button(0, true);
  v.app.frame();
  for (int i = 1; i <= 5; ++i) {
    v.platform.move_mouse(600.0f + 10.0f * i, 300);
    v.app.frame();
  }
  v.platform.set_button(0, false);
  v.app.frame();
  EXPECT_NE(v.app.state().camera().yaw_deg, yaw);
  EXPECT_EQ(v.app.state().selected_point(), -1);
  const double distance = v.app.state().camera().distance;
  v.platform.scroll(2.0f);
  v.app.frame();
  EXPECT_NEAR(v.app.state().camera().distance, distance * 0.81, 1e-9);
}

TEST(ViewerApp, SavedViewRendersTheSameThroughTheRenderPath) {
  const fs::path dir = temp_dir("view");
  render::Image viewer_image;
  {
    HeadlessViewer v;
    v.app.state().open_scene(testing::collide_scene());
    v.app.state().set_level(1);
    v.app.state().set_frame(15);
    v.app.state().select_point(5);
    v.app.state().layers().voxels = true;
    v.app.set_ui_visible(false);
    v.app.frame();
    viewer_image = v.app.read_pixels();
    v.app.state().save_view((dir / "view.json").string());
  }
  const render::ViewSpec view = render::load_view_spec((dir / "view.json").string());
  EXPECT_EQ(view.frame, 15);
  EXPECT_EQ(view.level, 1);
  EXPECT_EQ(view.picked_point, 5);
  EXPECT_EQ(view.width, kWidth);
  EXPECT_FALSE(view.camera.fit);
  const Scene scene = read_scene(testing::collide_scene());
  // As `dynscope render` draws it: the model's level view at the frame.
  const render::SceneRenderData data(scene, view,
                                     render::make_level_views(scene, view)->at(view.frame));
  render::GlContext& context = testing::osmesa(view.width, view.height);
  render::Renderer renderer(context, 4);
  const render::Image rendered =
      renderer.render_image(data.frame(view.frame, view), view.camera.camera);
  const render::ImageComparison c = render::compare_images(rendered, viewer_image, 2);
  EXPECT_GE(c.fraction_within, 0.999) << "max difference " << c.max_difference;

  // Reopening the saved view reproduces it.
  HeadlessViewer again;
  again.app.state().open_scene(testing::collide_scene());
  again.app.state().open_view((dir / "view.json").string());
  EXPECT_EQ(render::view_spec_to_json(again.app.state().current_view()),
            render::view_spec_to_json(view));
}

TEST(ViewerApp, BadFilesGiveClearErrorsAndKeepTheScene) {
  const fs::path dir = temp_dir("bad");
  HeadlessViewer v;
  v.app.state().open_scene(testing::collide_scene());
  const std::string missing = (dir / "missing.h5").string();
  try {
    v.app.state().open_scene(missing);
    FAIL() << "no error for a missing file";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("missing.h5"), std::string::npos) << e.what();
  }
  std::ofstream(dir / "garbage.h5") << "not hdf5";
  EXPECT_THROW(v.app.state().open_scene((dir / "garbage.h5").string()), Error);
  std::ofstream(dir / "bad.json") << "{\"frame\": \"x\"}";
  try {
    v.app.state().open_view((dir / "bad.json").string());
    FAIL() << "no error for a bad view";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.json"), std::string::npos) << e.what();
  }
  std::ofstream(dir / "far.json") << "{\"frame\": 500}";
  EXPECT_THROW(v.app.state().open_view((dir / "far.json").string()), ValueError);
  EXPECT_TRUE(v.app.state().has_scene());
  EXPECT_EQ(v.app.state().document().path, testing::collide_scene());
  EXPECT_EQ(v.app.state().current_frame(), 0);
  EXPECT_THROW(v.app.state().select_point(100000), ValueError);
  EXPECT_THROW(v.app.state().set_level(7), ValueError);
  // An action failing inside a frame becomes the popup's message, never an exception.
  v.app.request_screenshot((dir / "no_such_dir" / "shot.png").string());
  EXPECT_NO_THROW(v.app.frame());
  EXPECT_NE(v.app.last_error().find("shot.png"), std::string::npos) << v.app.last_error();
  EXPECT_NO_THROW(v.app.frame());
}

TEST(ViewerApp, ScreenshotWritesTheWholeWindow) {
  const fs::path dir = temp_dir("shot");
  HeadlessViewer v;
  v.app.state().open_scene(testing::collide_scene());
  v.app.frame();
  v.app.request_screenshot((dir / "shot.png").string());
  v.app.frame();
  const render::Image shot = render::read_png((dir / "shot.png").string());
  EXPECT_EQ(shot.width, kWidth);
  EXPECT_EQ(shot.height, kHeight);
  EXPECT_EQ(render::compare_images(shot, v.app.read_pixels(), 0).max_difference, 0);
  EXPECT_TRUE(v.app.last_error().empty());
}

}  // namespace
}  // namespace dynscope::app::viewer

namespace dynscope::app::viewer {
namespace {

// The window of a viewer drawing on the UI thread with `scene` open at `frame` (its own ImGui
// session: call it while no other viewer exists).
render::Image drawn_on_the_ui_thread(const std::string& scene, int frame, bool ui_visible) {
  HeadlessViewer direct;
  direct.app.set_ui_visible(ui_visible);
  direct.app.state().open_scene(scene);
  direct.app.state().set_frame(frame);
  direct.app.frame();
  direct.app.frame();
  return direct.app.read_pixels();
}

// With the view thread, a frame shows the newest image the thread finished; once it has drawn the
// current state, the window is the same picture as drawing on the UI thread.
TEST(ViewerApp, TheViewThreadShowsWhatDrawingOnTheUiThreadShows) {
  const render::Image expected = drawn_on_the_ui_thread(testing::collide_scene(), 40, true);

  HeadlessViewer v;
  v.app.state().open_scene(testing::collide_scene());
  v.app.set_view_thread(true);
  ASSERT_TRUE(v.app.view_thread());
  v.app.state().set_frame(40);
  v.app.frame();
  v.app.wait_for_view();
  v.app.frame();
  const render::Image shown = v.app.read_pixels();
  const render::ImageComparison diff = render::compare_images(shown, expected, 2);
  EXPECT_GE(diff.fraction_within, 0.9995) << "max difference " << diff.max_difference;
  EXPECT_TRUE(v.app.last_error().empty()) << v.app.last_error();
}

TEST(ViewerApp, WithTheViewThreadScrubbingUploadsNothingAndTheNewestFrameIsShown) {
  HeadlessViewer v;
  v.app.state().open_scene(testing::collide_scene());
  v.app.set_ui_visible(false);
  v.app.set_view_thread(true);
  v.app.state().set_frame(0);
  v.app.frame();
  v.app.wait_for_view();
  v.app.frame();
  const render::Image first = v.app.read_pixels();
  const int64_t uploads = v.app.upload_count();
  const int64_t images = v.app.view_images();
  // Frames handed over faster than they are drawn: the UI thread never waits for them.
  for (int k = 1; k <= 40; ++k) {
    v.app.state().set_frame(k);
    v.app.frame();
  }
  v.app.wait_for_view();
  v.app.frame();
  EXPECT_GT(v.app.view_images(), images);
  EXPECT_EQ(v.app.upload_count(), uploads);
  const render::Image at_40 = v.app.read_pixels();
  EXPECT_LT(render::compare_images(at_40, first, 8).fraction_within, 0.999);
  // The same frame drawn directly is the same picture.
  v.app.set_view_thread(false);
  v.app.frame();
  EXPECT_EQ(render::compare_images(v.app.read_pixels(), at_40, 2).fraction_within, 1.0);
  // An idle viewer draws nothing new.
  v.app.set_view_thread(true);
  v.app.frame();
  v.app.wait_for_view();
  const int64_t idle = v.app.view_images();
  for (int i = 0; i < 5; ++i) v.app.frame();
  v.app.wait_for_view();
  EXPECT_EQ(v.app.view_images(), idle);
}

TEST(ViewerApp, AScreenshotWithTheViewThreadShowsItsOwnFrame) {
  const fs::path dir = temp_dir("thread_shot");
  {  // one viewer (ImGui session) at a time
    HeadlessViewer direct;
    direct.app.state().open_scene(testing::collide_scene());
    direct.app.state().set_frame(25);
    direct.app.frame();
    direct.app.request_screenshot((dir / "direct.png").string());
    direct.app.frame();
  }

  HeadlessViewer v;
  v.app.state().open_scene(testing::collide_scene());
  v.app.set_view_thread(true);
  v.app.frame();
  v.app.state().set_frame(25);  // no wait: the screenshot's frame waits for its own view
  v.app.request_screenshot((dir / "thread.png").string());
  v.app.frame();
  const render::ImageComparison diff =
      render::compare_images(render::read_png((dir / "thread.png").string()),
                             render::read_png((dir / "direct.png").string()), 2);
  EXPECT_GE(diff.fraction_within, 0.9995) << "max difference " << diff.max_difference;
}

// The view thread holds what it draws (shared, immutable point series and meshes): opening
// another document or switching the thread off while it draws the old one is safe, and the next
// views are of the new document.
TEST(ViewerApp, OpeningAnotherSceneWhileTheViewThreadDrawsIsSafe) {
  const std::string other = std::string(DYNSCOPE_SOURCE_DIR) + "/assets/scenes/collide_0001.h5";
  const render::Image expected = drawn_on_the_ui_thread(other, 0, false);
  HeadlessViewer v;
  v.app.set_ui_visible(false);
  v.app.set_view_thread(true);
  for (int round = 0; round < 3; ++round) {
    v.app.state().open_scene(testing::collide_scene());
    v.app.frame();  // the thread starts drawing collide_0000
    v.app.state().open_scene(other);
    v.app.frame();
  }
  v.app.wait_for_view();
  v.app.frame();
  EXPECT_GE(render::compare_images(v.app.read_pixels(), expected, 2).fraction_within, 0.9995);
  v.app.state().open_scene(testing::collide_scene());
  v.app.frame();
  v.app.set_view_thread(false);  // stops the thread while it may be drawing
  v.app.frame();
  EXPECT_TRUE(v.app.last_error().empty()) << v.app.last_error();
}

}  // namespace
}  // namespace dynscope::app::viewer
