// Rollout files: exact write→read round trip and clear errors for corrupt files.
#include "engine/io/rollout_file.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include "engine/core/error.h"
#include "engine/io/h5_util.h"

namespace dynscope {
namespace {

namespace fs = std::filesystem;

std::string temp_path(const std::string& name) {
  return (fs::temp_directory_path() / ("dynscope_rollout_" + name + ".h5")).string();
}

Rollout make_rollout(bool contact) {
  Rollout r;
  r.scene_path = "scenes/drop_0000.h5";
  r.checkpoint_path = "model.pt";
  r.model_config = R"({"kind":"pointconv"})";
  r.scenario = "drop";
  r.dt_s = 0.01;
  r.observed_frames = 3;
  r.sampling_voxel = 0.05;
  const int n = 5, t = 4;
  r.rest = Points::Random(n, 3);
  r.object_ids = {1, 1, 2, 2, 2};
  r.faces.resize(1, 3);
  r.faces << 0, 1, 2;
  for (int f = 0; f < t; ++f) {
    r.predicted.push_back(Points::Random(n, 3));
    r.truth.push_back(Points::Random(n, 3));
    Pose a, b;
    a.position = Vec3(0.1 * f, 1.0 / 3.0, -2);
    a.rotation = Quat(Eigen::AngleAxisd(0.3 * f, Vec3(1, 2, 3).normalized()));
    r.poses.push_back({a, b});
    r.point_error.push_back(0.125 * f + 1e-17);
    if (contact) {
      r.contact_distance_truth.push_back(0.5 - 0.1 * f);
      r.contact_distance_predicted.push_back(0.6 - 0.1 * f);
    }
  }
  r.pose_object_ids = {1, 2};
  r.pose_rigid = {1, 0};
  if (contact) r.static_points = {0, 0, 1, 1, 1};  // the other variant: a file without the flags
  return r;
}

void expect_equal(const Rollout& a, const Rollout& b) {
  EXPECT_EQ(a.scene_path, b.scene_path);
  EXPECT_EQ(a.checkpoint_path, b.checkpoint_path);
  EXPECT_EQ(a.model_config, b.model_config);
  EXPECT_EQ(a.scenario, b.scenario);
  EXPECT_EQ(a.dt_s, b.dt_s);
  EXPECT_EQ(a.observed_frames, b.observed_frames);
  EXPECT_EQ(a.sampling_voxel, b.sampling_voxel);
  EXPECT_EQ(a.rest, b.rest);
  EXPECT_EQ(a.object_ids, b.object_ids);
  EXPECT_EQ(a.faces, b.faces);
  EXPECT_EQ(a.static_points, b.static_points);
  ASSERT_EQ(a.num_frames(), b.num_frames());
  for (int f = 0; f < a.num_frames(); ++f) {
    EXPECT_EQ(a.predicted[f], b.predicted[f]);
    EXPECT_EQ(a.truth[f], b.truth[f]);
    for (int o = 0; o < a.num_objects(); ++o) {
      EXPECT_EQ(a.poses[f][o].position, b.poses[f][o].position);
      EXPECT_EQ(a.poses[f][o].rotation.coeffs(), b.poses[f][o].rotation.coeffs());
    }
  }
  EXPECT_EQ(a.pose_object_ids, b.pose_object_ids);
  EXPECT_EQ(a.pose_rigid, b.pose_rigid);
  EXPECT_EQ(a.point_error, b.point_error);
  EXPECT_EQ(a.contact_distance_truth, b.contact_distance_truth);
  EXPECT_EQ(a.contact_distance_predicted, b.contact_distance_predicted);
}

TEST(RolloutFileTest, WriteReadIsExact) {
  for (bool contact : {true, false}) {
    const Rollout r = make_rollout(contact);
    const std::string path = temp_path(contact ? "contact" : "plain");
    write_rollout(r, path);
    EXPECT_TRUE(is_rollout_file(path));
    expect_equal(r, read_rollout(path));
  }
}

TEST(RolloutFileTest, InconsistentRolloutIsNotWritten) {
  Rollout r = make_rollout(true);
  r.point_error.pop_back();
  const std::string path = temp_path("bad");
  fs::remove(path);
  EXPECT_THROW(write_rollout(r, path), ValueError);
  EXPECT_FALSE(fs::exists(path));
}

TEST(RolloutFileTest, StaticFlagsAreOnePerPointAndZeroOrOne) {
  Rollout r = make_rollout(true);
  r.static_points.pop_back();
  const std::string bad = temp_path("static_short");
  fs::remove(bad);
  EXPECT_THROW(write_rollout(r, bad), ValueError);
  EXPECT_FALSE(fs::exists(bad));

  const std::string path = temp_path("static_two");
  write_rollout(make_rollout(true), path);
  {
    h5::Handle file(H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT));
    ASSERT_TRUE(file.valid());
    h5::Handle ds(H5Dopen2(file.get(), "points/static", H5P_DEFAULT));
    ASSERT_TRUE(ds.valid());
    const uint8_t flags[5] = {0, 0, 1, 2, 1};
    ASSERT_GE(H5Dwrite(ds.get(), H5T_NATIVE_UINT8, H5S_ALL, H5S_ALL, H5P_DEFAULT, flags), 0);
  }
  try {
    read_rollout(path);
    FAIL();
  } catch (const FormatError& e) {
    EXPECT_EQ(e.field(), "points/static");
    EXPECT_NE(std::string(e.what()).find("point 3"), std::string::npos) << e.what();
  }
}

TEST(RolloutFileTest, FindsTheSceneAtItsPathOrNextToTheRollout) {
  const fs::path dir = fs::temp_directory_path() / "dynscope_rollout_scene_lookup";
  fs::remove_all(dir);
  fs::create_directories(dir / "moved");
  Rollout r = make_rollout(false);
  r.scene_path = (dir / "scene.h5").string();
  EXPECT_EQ(find_rollout_scene(r, (dir / "moved" / "r.h5").string()), "") << "nothing exists yet";
  std::ofstream(dir / "moved" / "scene.h5") << "x";
  EXPECT_EQ(find_rollout_scene(r, (dir / "moved" / "r.h5").string()),
            (dir / "moved" / "scene.h5").string());
  std::ofstream(dir / "scene.h5") << "x";
  EXPECT_EQ(find_rollout_scene(r, (dir / "moved" / "r.h5").string()), r.scene_path)
      << "the stored path comes first";
  r.scene_path.clear();
  EXPECT_EQ(find_rollout_scene(r, (dir / "moved" / "r.h5").string()), "");
  fs::remove_all(dir);
}

TEST(RolloutFileTest, CorruptFilesGiveClearErrors) {
  const std::string text = temp_path("text");
  std::ofstream(text) << "not hdf5";
  EXPECT_THROW(read_rollout(text), IoError);
  EXPECT_FALSE(is_rollout_file(text));
  EXPECT_THROW(read_rollout(temp_path("missing_file")), IoError);

  // A valid HDF5 file of another kind names the format attribute.
  const std::string other = temp_path("other");
  {
    h5::Group root = h5::Group::create_file(other);
    root.write_attribute("format", std::string("dynscope-scene"));
    root.close();
  }
  try {
    read_rollout(other);
    FAIL();
  } catch (const FormatError& e) {
    EXPECT_EQ(e.field(), "@format");
  }

  // A rollout with a truncated dataset names it.
  const std::string path = temp_path("truncated");
  const Rollout r = make_rollout(false);
  write_rollout(r, path);
  {
    h5::Handle file(H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT));
    ASSERT_TRUE(file.valid());
    ASSERT_GE(H5Ldelete(file.get(), "metrics/point_error", H5P_DEFAULT), 0);
  }
  try {
    read_rollout(path);
    FAIL();
  } catch (const FormatError& e) {
    EXPECT_EQ(e.field(), "metrics/point_error");
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos);
  }
}

// The field named by the FormatError that reading `r` back throws ("" if none).
std::string read_back_error(const Rollout& r, const std::string& name) {
  const std::string path = temp_path(name);
  write_rollout(r, path);
  try {
    read_rollout(path);
  } catch (const FormatError& e) {
    return e.field();
  }
  return "";
}

TEST(RolloutFileTest, NonFiniteMetricsAndPosesAreRejectedOnRead) {
  Rollout nan_error = make_rollout(true);
  nan_error.point_error[2] = std::nan("");
  EXPECT_EQ(read_back_error(nan_error, "nan_error"), "metrics/point_error");

  Rollout inf_contact = make_rollout(true);
  inf_contact.contact_distance_predicted[1] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(read_back_error(inf_contact, "inf_contact"), "metrics/contact_distance_predicted");

  Rollout nan_pose = make_rollout(false);
  nan_pose.poses[1][0].position.x() = std::nan("");
  EXPECT_EQ(read_back_error(nan_pose, "nan_pose"), "poses/fitted");

  Rollout unposed = make_rollout(false);
  unposed.object_ids[4] = 7;  // no pose for object 7
  EXPECT_EQ(read_back_error(unposed, "unposed"), "points/object_ids");

  EXPECT_EQ(read_back_error(make_rollout(true), "good"), "");
}

}  // namespace
}  // namespace dynscope
