// Tests of the batch renderer behind `dynscope render`: option parsing, outputs, bad input.
#include "render/batch_render.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "engine/core/error.h"
#include "engine/io/scene_file.h"
#include "render/png_io.h"
#include "render_test_util.h"

namespace dynscope::render {
namespace {

namespace fs = std::filesystem;

TEST(BatchRender, ParsesFrameRanges) {
  EXPECT_EQ(parse_frame_range("2:5", 10), std::make_pair(2, 4));
  EXPECT_EQ(parse_frame_range("7:", 10), std::make_pair(7, 9));
  EXPECT_EQ(parse_frame_range(":3", 10), std::make_pair(0, 2));
  EXPECT_EQ(parse_frame_range("4", 10), std::make_pair(4, 4));
  EXPECT_EQ(parse_frame_range("-2:", 10), std::make_pair(8, 9));
  for (const char* bad : {"5:2", "x", "1:y", "10", "0:11", "3:3"}) {
    EXPECT_THROW(parse_frame_range(bad, 10), ValueError) << bad;
  }
}

TEST(BatchRender, ParsesImageSizes) {
  EXPECT_EQ(parse_image_size("1280x720"), std::make_pair(1280, 720));
  for (const char* bad : {"1280", "0x5", "ax5", "5x", "20000x10"}) {
    EXPECT_THROW(parse_image_size(bad), ValueError) << bad;
  }
}

TEST(BatchRender, CorruptSceneFileNamesTheFile) {
  const fs::path dir = fs::temp_directory_path() / "dynscope_batch_corrupt";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string scene = (dir / "broken.h5").string();
  std::ofstream(scene) << "\x89HDF\r\n\x1a\n this is not really hdf5";
  BatchRenderOptions options;
  options.scene_path = scene;
  options.out_dir = (dir / "out").string();
  options.progress = false;
  try {
    render_scene_file(testing::osmesa(), options);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(scene), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir / "out" / "frame_0000.png"));
}

TEST(BatchRender, WritesFramesContactSheetAndResolvedView) {
  const fs::path dir = fs::temp_directory_path() / "dynscope_batch_ok";
  fs::remove_all(dir);
  fs::create_directories(dir);
  Scene scene = testing::shapes_scene(4);
  for (int f = 0; f < 4; ++f) scene.trajectories[0].poses[f].position.z() = 0.2 + 0.1 * f;
  write_scene(scene, (dir / "scene.h5").string());
  BatchRenderOptions options;
  options.scene_path = (dir / "scene.h5").string();
  options.out_dir = (dir / "out").string();
  options.frames = "1:4";
  options.width = 96;
  options.height = 64;
  options.samples = 0;
  options.progress = false;
  const BatchRenderResult r = render_scene_file(testing::osmesa(), options);
  ASSERT_EQ(r.frame_files.size(), 3u);
  EXPECT_EQ(fs::path(r.frame_files[0]).filename(), "frame_0001.png");
  const Image first = read_png(r.frame_files[0]);
  EXPECT_EQ(first.width, 96);
  EXPECT_EQ(first.height, 64);
  EXPECT_NE(first.rgba, read_png(r.frame_files[2]).rgba);  // the box moved
  ASSERT_FALSE(r.contact_sheet.empty());
  EXPECT_TRUE(fs::exists(r.contact_sheet));
  const ViewSpec view = load_view_spec(r.view_file);
  EXPECT_FALSE(view.camera.fit);
  EXPECT_EQ(view.width, 96);
  if (find_on_path("ffmpeg").empty()) {
    ASSERT_EQ(r.notes.size(), 1u);
    EXPECT_NE(r.notes[0].find("ffmpeg"), std::string::npos);
  }
  options.frames = "9:";
  EXPECT_THROW(render_scene_file(testing::osmesa(), options), ValueError);
}

}  // namespace
}  // namespace dynscope::render
