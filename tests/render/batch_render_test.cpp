// Tests of the batch renderer behind `dynscope render`: option parsing, scene and rollout outputs,
// bad input.
#include "render/batch_render.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "engine/core/error.h"
#include "engine/io/rollout_file.h"
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
    EXPECT_TRUE(r.video.empty());
  } else {
    // ffmpeg is optional at run time; where it is installed the MP4 must really be written.
    EXPECT_TRUE(r.notes.empty()) << r.notes[0];
    ASSERT_FALSE(r.video.empty());
    EXPECT_GT(fs::file_size(r.video), 0u);
    EXPECT_FALSE(fs::exists(dir / "out" / ".render.tmp.mp4"));
  }
  options.frames = "9:";
  EXPECT_THROW(render_scene_file(testing::osmesa(), options), ValueError);
}

// Two 4x4x2 point blocks over 4 frames; 2 observed frames copy the truth, then the prediction of
// object 1 drifts upwards by 0.3 per frame (object 0 stays exact).
Rollout drifting_rollout() {
  Rollout r;
  r.scene_path = "missing_scene.h5";
  r.scenario = "drop";
  r.dt_s = 0.1;
  r.observed_frames = 2;
  r.sampling_voxel = 0.1;
  const int per_object = 32;
  r.rest = Points(2 * per_object, 3);
  for (int o = 0; o < 2; ++o) {
    for (int i = 0; i < per_object; ++i) {
      r.rest.row(o * per_object + i) = Vec3(0.1 * (i % 4), 0.1 * ((i / 4) % 4), 0.1 * (i / 16));
      r.object_ids.push_back(o);
    }
  }
  r.pose_object_ids = {0, 1};
  r.pose_rigid = {1, 1};
  for (int f = 0; f < 4; ++f) {
    Points truth = r.rest;
    truth.col(0).tail(per_object).array() += 0.8;
    truth.col(2).array() += 0.05;
    Points predicted = truth;
    const double drift = f < r.observed_frames ? 0.0 : 0.3 * (f - 1);
    predicted.col(2).tail(per_object).array() += drift;
    r.truth.push_back(truth);
    r.predicted.push_back(predicted);
    r.point_error.push_back(drift / 2.0);  // half of the points are off by `drift`
    r.poses.push_back({Pose{Vec3::Zero(), Quat::Identity()}, Pose{Vec3::Zero(), Quat::Identity()}});
  }
  return r;
}

// Pixels whose chromaticity (rgb / sum) is within `tolerance` of `color`'s and that are not dark:
// the shading scales a sphere's colour, so the hue survives but the brightness does not.
int count_pixels_like(const Image& image, const Color& color, float tolerance) {
  const Color target = color / color.sum();
  int count = 0;
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      const uint8_t* p = image.pixel(x, y);
      const Color c(p[0], p[1], p[2]);
      if (c.sum() < 60.0f) continue;
      if ((c / c.sum() - target).cwiseAbs().maxCoeff() < tolerance) ++count;
    }
  }
  return count;
}

TEST(BatchRender, RendersRolloutColouredByError) {
  const fs::path dir = fs::temp_directory_path() / "dynscope_batch_rollout";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string path = (dir / "rollout.h5").string();
  write_rollout(drifting_rollout(), path);
  ASSERT_TRUE(is_rollout_file(path));
  BatchRenderOptions options;
  options.scene_path = path;
  options.out_dir = (dir / "out").string();
  options.width = 160;
  options.height = 120;
  options.samples = 0;
  options.progress = false;
  options.video = false;
  const BatchRenderResult r = render_file(testing::osmesa(), options);
  ASSERT_EQ(r.frame_files.size(), 4u);
  for (const std::string& file : r.frame_files) {
    const Image image = read_png(file);
    EXPECT_EQ(image.width, 160);
    EXPECT_EQ(image.height, 120);
  }
  ASSERT_FALSE(r.contact_sheet.empty());
  EXPECT_TRUE(fs::exists(r.contact_sheet));

  // Frame 0 has no error, frame 3 the rollout's largest: only frame 3 shows the colormap's top.
  const Image exact = read_png(r.frame_files[0]);
  const Image drifted = read_png(r.frame_files[3]);
  EXPECT_NE(exact.rgba, drifted.rgba);
  const Color top = colormap("viridis", 1.0f);
  EXPECT_EQ(count_pixels_like(exact, top, 0.05f), 0);
  EXPECT_GT(count_pixels_like(drifted, top, 0.05f), 20);

  const ViewSpec view = load_view_spec(r.view_file);
  EXPECT_TRUE(view.layers.prediction);
  EXPECT_TRUE(view.layers.error);
  EXPECT_TRUE(view.layers.ghost);
  EXPECT_FALSE(view.camera.fit);
}

TEST(BatchRender, CorruptRolloutFileNamesTheFile) {
  const fs::path dir = fs::temp_directory_path() / "dynscope_batch_rollout_corrupt";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string path = (dir / "rollout.h5").string();
  write_rollout(drifting_rollout(), path);
  // Cutting the file keeps the header (and perhaps the format attribute) but loses the data.
  fs::resize_file(path, fs::file_size(path) / 2);
  BatchRenderOptions options;
  options.scene_path = path;
  options.out_dir = (dir / "out").string();
  options.progress = false;
  for (auto* render : {&render_rollout_file, &render_file}) {
    try {
      render(testing::osmesa(), options);
      ADD_FAILURE() << "expected an error";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
  }
  EXPECT_FALSE(fs::exists(dir / "out" / "frame_0000.png"));
}

}  // namespace
}  // namespace dynscope::render
