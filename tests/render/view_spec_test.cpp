// Tests of the view spec JSON: round trip, defaults, unknown keys, clear errors.
#include "render/view_spec.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "engine/core/error.h"

namespace dynscope::render {
namespace {

namespace fs = std::filesystem;

std::string write_text(const std::string& name, const std::string& text) {
  const fs::path path = fs::temp_directory_path() / ("dynscope_view_" + name);
  std::ofstream(path) << text;
  return path.string();
}

TEST(ViewSpec, SaveLoadRoundTripKeepsEveryField) {
  ViewSpec v;
  v.frame = 7;
  v.camera.fit = false;
  v.camera.camera.target = Vec3(1, -2, 0.5);
  v.camera.camera.distance = 3.25;
  v.camera.camera.yaw_deg = 12;
  v.camera.camera.pitch_deg = -30;
  v.camera.camera.fov_deg = 55;
  v.width = 320;
  v.height = 200;
  v.background = Color(0.1f, 0.2f, 0.3f);
  v.layers.error = true;
  v.layers.ghost = true;
  v.layers.meshes = false;
  v.colormap = "turbo";
  v.auto_range = false;
  v.range_min = 0.01f;
  v.range_max = 0.5f;
  v.picked_point = 42;
  v.level = 2;
  v.labels = false;
  v.point_radius = 0.03f;
  v.voxel = 0.04;
  const std::string path = (fs::temp_directory_path() / "dynscope_view_roundtrip.json").string();
  save_view_spec(v, path);
  const ViewSpec back = load_view_spec(path);
  EXPECT_EQ(view_spec_to_json(back), view_spec_to_json(v));
  EXPECT_EQ(back.picked_point, 42);
  EXPECT_FALSE(back.camera.fit);
  EXPECT_TRUE(back.camera.camera.target.isApprox(Vec3(1, -2, 0.5)));
}

TEST(ViewSpec, MissingKeysDefaultAndUnknownKeysAreIgnored) {
  const std::string path =
      write_text("partial.json", R"({"frame": 3, "layers": {"voxels": true, "sparkles": 1},
                                    "future_option": {"x": 1}})");
  const ViewSpec v = load_view_spec(path);
  EXPECT_EQ(v.frame, 3);
  EXPECT_TRUE(v.layers.voxels);
  EXPECT_TRUE(v.layers.meshes);
  EXPECT_EQ(v.width, ViewSpec().width);
  EXPECT_TRUE(v.camera.fit);
  EXPECT_EQ(v.colormap, "viridis");
}

TEST(ViewSpec, ExplicitCameraTurnsFitOffAndPresetSetsAngles) {
  ViewSpec v = view_spec_from_json(nlohmann::json::parse(R"({"camera": {"distance": 2}})"), "t");
  EXPECT_FALSE(v.camera.fit);
  v = view_spec_from_json(nlohmann::json::parse(R"({"camera": {"preset": "top"}})"), "t");
  EXPECT_TRUE(v.camera.fit);
  EXPECT_DOUBLE_EQ(v.camera.camera.pitch_deg, 90.0);
}

void expect_format_error(const std::string& text, const std::string& field) {
  const std::string path = write_text("bad.json", text);
  try {
    load_view_spec(path);
    FAIL() << "expected FormatError for " << text;
  } catch (const FormatError& e) {
    EXPECT_EQ(e.path(), path);
    EXPECT_EQ(e.field(), field) << e.what();
  }
}

TEST(ViewSpec, BadInputNamesFileAndKey) {
  expect_format_error(R"({"frame": 1,)", "json");
  expect_format_error(R"([1, 2])", "(top level)");
  expect_format_error(R"({"camera": {"distance": "far"}})", "camera.distance");
  expect_format_error(R"({"camera": {"target": [1, 2]}})", "camera.target");
  expect_format_error(R"({"camera": {"preset": "bottom"}})", "camera.preset");
  expect_format_error(R"({"image": {"width": 0}})", "image");
  // The same pixel ceiling as --size: 16384 x 16384 once passed and asked for a 1 GiB buffer.
  expect_format_error(R"({"image": {"width": 16384, "height": 16384}})", "image");
  EXPECT_NO_THROW(view_spec_from_json(
      nlohmann::json::parse(R"({"image": {"width": 8192, "height": 2048}})"), "v.json"));
  expect_format_error(R"({"colormap": {"name": "jet"}})", "colormap");
  expect_format_error(R"({"colormap": {"range": [1, 0]}})", "colormap.range");
  expect_format_error(R"({"layers": {"grid": "yes"}})", "layers.grid");
  expect_format_error(R"({"frame": 1.5})", "frame");
  EXPECT_THROW(load_view_spec("/nonexistent/view.json"), IoError);
}

}  // namespace
}  // namespace dynscope::render
