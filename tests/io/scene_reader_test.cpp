// Tests of the shared scene reader: optional fields default, malformed files give clear errors.
#include "engine/io/scene_reader.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "engine/io/scene_file.h"
#include "tests/io/io_test_util.h"

namespace dynscope {
namespace {

using test::error_of;
using test::expect_contains;

class SceneReaderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    scene_ = test::make_test_scene();
    path_ = dir_.file("scene.h5");
    write_scene(scene_, path_);
  }

  // The FormatError message of reading the (edited) file; it must name the file and `field`.
  std::string format_error(const std::string& field) {
    const std::string message = error_of<FormatError>([&] { read_scene(path_); });
    expect_contains(message, {path_ + ": " + field});
    return message;
  }

  test::TempDir dir_;
  Scene scene_;
  std::string path_;
};

TEST_F(SceneReaderTest, MissingOptionalFieldsGetDefaults) {
  for (const char* name :
       {"static/names", "static/roles", "static/target_id", "static/zone_id", "static/rigid",
        "static/scale", "static/mass", "static/friction", "static/restitution", "static/color"}) {
    test::h5_delete(path_, name);
  }
  for (int t = 0; t < 5; ++t) test::h5_delete(path_, "frames/000" + std::to_string(t) + "/labels");
  for (const char* name : {"scenario", "seed", "num_frames", "format", "format_version"}) {
    test::h5_delete_attribute(path_, "/", name);
  }
  // Without the rigid flags the sheet counts as rigid and its identity/centroid rows are its pose.
  const Scene back = read_scene(path_);
  const Object defaults;
  ASSERT_EQ(back.objects.size(), 3u);
  EXPECT_EQ(back.objects[0].name, "object_3");
  EXPECT_EQ(back.objects[1].role, Role::kOther);
  EXPECT_TRUE(back.objects[2].rigid);
  EXPECT_EQ(back.objects[1].scale, Vec3::Ones());
  EXPECT_EQ(back.objects[0].mass, defaults.mass);
  EXPECT_EQ(back.objects[0].friction, defaults.friction);
  EXPECT_EQ(back.objects[0].restitution, defaults.restitution);
  EXPECT_EQ(back.objects[0].color, defaults.color);
  EXPECT_EQ(back.scenario, "");
  EXPECT_EQ(back.seed, 0u);
  EXPECT_TRUE(back.labels.empty());
  EXPECT_EQ(back.objects[0].mesh.vertices, scene_.objects[0].mesh.vertices);
  EXPECT_EQ(back.trajectories[0].poses[3].position, scene_.trajectories[0].poses[3].position);
}

TEST_F(SceneReaderTest, RolesFallBackToTargetAndZoneIds) {
  test::h5_delete(path_, "static/roles");
  const Scene back = read_scene(path_);
  EXPECT_EQ(back.objects[0].role, Role::kTarget);
  EXPECT_EQ(back.objects[1].role, Role::kZone);
  EXPECT_EQ(back.objects[2].role, Role::kOther);
}

TEST_F(SceneReaderTest, AcceptsFloat32AndIntegerTypes) {
  // h5py users often write float32 positions and int64 faces.
  test::h5_put(path_, "frames/0001/objects/positions", {3, 3}, {0.5, 1.25, -2, 0, 0, 0, 3, 3, 3},
               H5T_IEEE_F32LE);
  test::h5_put(path_, "static/mesh/faces_0", {1, 3}, {0, 1, 2}, H5T_STD_I64LE);
  test::h5_put(path_, "static/mass", {3}, {1, 2, 3}, H5T_STD_I32LE);
  const Scene back = read_scene(path_);
  EXPECT_EQ(back.trajectories[0].poses[1].position, Vec3(0.5, 1.25, -2));
  EXPECT_EQ(back.objects[0].mesh.num_faces(), 1);
  EXPECT_EQ(back.objects[2].mass, 3.0);
}

TEST_F(SceneReaderTest, NonUnitQuaternionsAreNormalised) {
  test::h5_put(path_, "frames/0000/objects/rotations", {3, 4}, {2, 0, 0, 0, 0, 0, 0, 3, 1, 0, 0, 0},
               H5T_IEEE_F32LE);
  const Scene back = read_scene(path_);
  EXPECT_EQ(back.trajectories[0].poses[0].rotation.coeffs(), Quat::Identity().coeffs());
  EXPECT_DOUBLE_EQ(back.trajectories[1].poses[0].rotation.z(), 1.0);
}

TEST_F(SceneReaderTest, MissingFileIsAnIoError) {
  const std::string missing = dir_.file("nope.h5");
  expect_contains(error_of<IoError>([&] { read_scene(missing); }), {missing, "no such file"});
}

TEST_F(SceneReaderTest, NonHdf5FileIsAnIoError) {
  const std::string text = dir_.file("notes.h5");
  test::write_text(text, "this is not an HDF5 file\n");
  expect_contains(error_of<IoError>([&] { read_scene(text); }), {text, "not an HDF5 file"});
  const std::string binary = dir_.file("random.bin");
  std::string bytes;
  for (int i = 0; i < 4096; ++i) bytes.push_back(static_cast<char>((i * 7919) % 251));
  test::write_text(binary, bytes);
  expect_contains(error_of<IoError>([&] { read_scene(binary); }), {binary});
}

TEST_F(SceneReaderTest, TruncatedFileIsAnIoErrorAtEveryLength) {
  const auto size = std::filesystem::file_size(path_);
  for (const double fraction : {0.9, 0.5, 0.1, 0.01}) {
    const std::string cut = dir_.file("cut.h5");
    std::filesystem::copy_file(path_, cut, std::filesystem::copy_options::overwrite_existing);
    std::filesystem::resize_file(cut, static_cast<uintmax_t>(static_cast<double>(size) * fraction));
    expect_contains(error_of<IoError>([&] { read_scene(cut); }), {cut + ": "});
  }
}

TEST_F(SceneReaderTest, MissingStaticGroup) {
  test::h5_delete(path_, "static");
  expect_contains(format_error("static"), {"missing group"});
}

TEST_F(SceneReaderTest, MissingObjectIds) {
  test::h5_delete(path_, "static/object_ids");
  expect_contains(format_error("static/object_ids"), {"missing dataset"});
}

TEST_F(SceneReaderTest, MissingFrames) {
  test::h5_delete(path_, "frames");
  format_error("frames");
}

TEST_F(SceneReaderTest, MissingMesh) {
  test::h5_delete(path_, "static/mesh/vertices_1");
  format_error("static/mesh/vertices_1");
}

TEST_F(SceneReaderTest, MissingDt) {
  test::h5_delete_attribute(path_, "/", "dt");
  format_error("@dt");
}

TEST_F(SceneReaderTest, WrongPositionShape) {
  test::h5_put(path_, "frames/0002/objects/positions", {5, 2}, std::vector<double>(10, 0.0));
  expect_contains(format_error("frames/0002/objects/positions"),
                  {"expected [3,3] numbers, got [5,2] float64"});
}

TEST_F(SceneReaderTest, WrongRotationShape) {
  test::h5_put(path_, "frames/0001/objects/rotations", {3, 3}, std::vector<double>(9, 0.0));
  expect_contains(format_error("frames/0001/objects/rotations"), {"[3,4]", "[3,3]"});
}

TEST_F(SceneReaderTest, WrongStaticCount) {
  test::h5_put(path_, "static/mass", {4}, {1, 2, 3, 4});
  expect_contains(format_error("static/mass"), {"expected [3] numbers, got [4] float64"});
}

TEST_F(SceneReaderTest, WrongElementType) {
  test::h5_edit(path_, [](hid_t f) {
    H5Ldelete(f, "static/object_ids", H5P_DEFAULT);
    const hsize_t dims[1] = {3};
    const hid_t space = H5Screate_simple(1, dims, nullptr);
    const hid_t ds = H5Dcreate2(f, "static/object_ids", H5T_IEEE_F64LE, space, H5P_DEFAULT,
                                H5P_DEFAULT, H5P_DEFAULT);
    const double ids[3] = {3, 11, 40};
    H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, ids);
    H5Dclose(ds);
    H5Sclose(space);
  });
  expect_contains(format_error("static/object_ids"), {"expected [N] integers, got [3] float64"});
}

TEST_F(SceneReaderTest, NanPosition) {
  test::h5_put(path_, "frames/0003/objects/positions", {3, 3},
               {0, 0, 0, 0, std::nan(""), 0, 0, 0, 0});
  expect_contains(format_error("frames/0003/objects/positions"), {"non-finite", "row 1"});
}

TEST_F(SceneReaderTest, NanVertex) {
  test::h5_put(path_, "static/mesh/vertices_2", {4, 3},
               {0, 0, 0, 1, 0, 0, 1, 1, HUGE_VAL, 0, 1, 0});
  expect_contains(format_error("static/mesh/vertices_2"), {"non-finite", "row 2"});
}

TEST_F(SceneReaderTest, ZeroQuaternion) {
  test::h5_put(path_, "frames/0000/objects/rotations", {3, 4}, std::vector<double>(12, 0.0));
  expect_contains(format_error("frames/0000/objects/rotations"), {"zero quaternion"});
}

TEST_F(SceneReaderTest, FaceIndexOutOfRange) {
  test::h5_put(path_, "static/mesh/faces_2", {1, 3}, {0, 1, 4}, H5T_STD_I32LE);
  expect_contains(format_error("static/mesh/faces_2"), {"index 4", "4 vertices"});
}

TEST_F(SceneReaderTest, DuplicateObjectIds) {
  test::h5_put(path_, "static/object_ids", {3}, {3, 11, 3}, H5T_STD_I32LE);
  expect_contains(format_error("static/object_ids"), {"duplicate id 3"});
}

TEST_F(SceneReaderTest, UnknownRole) {
  test::h5_edit(path_, [](hid_t f) {
    H5Ldelete(f, "static/roles", H5P_DEFAULT);
    const hid_t type = H5Tcopy(H5T_C_S1);
    H5Tset_size(type, 8);
    const hsize_t dims[1] = {3};
    const hid_t space = H5Screate_simple(1, dims, nullptr);
    const hid_t ds =
        H5Dcreate2(f, "static/roles", type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    const char roles[24] = "target\0\0zone\0\0\0\0bouncer";
    H5Dwrite(ds, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, roles);
    H5Dclose(ds);
    H5Sclose(space);
    H5Tclose(type);
  });
  expect_contains(format_error("static/roles"), {"index 2", "bouncer"});
}

TEST_F(SceneReaderTest, TargetIdNotAnObject) {
  test::h5_delete(path_, "static/roles");
  test::h5_put(path_, "static/target_id", {}, {99}, H5T_STD_I32LE);
  expect_contains(format_error("static/target_id"), {"99"});
}

TEST_F(SceneReaderTest, MissingFrameInTheSequence) {
  test::h5_delete(path_, "frames/0002");
  expect_contains(format_error("frames/0002"), {"missing frame"});
}

TEST_F(SceneReaderTest, BadFrameName) {
  test::h5_edit(path_, [](hid_t f) {
    H5Lmove(f, "frames/0004", f, "frames/last", H5P_DEFAULT, H5P_DEFAULT);
  });
  format_error("frames/last");
}

TEST_F(SceneReaderTest, NumFramesMismatch) {
  test::h5_delete(path_, "frames/0004");
  format_error("@num_frames");
}

TEST_F(SceneReaderTest, MissingParticles) {
  test::h5_delete(path_, "frames/0001/particles/2");
  format_error("frames/0001/particles/2");
}

TEST_F(SceneReaderTest, ParticleCountMustMatchTheMesh) {
  test::h5_put(path_, "frames/0001/particles/2", {3, 3}, std::vector<double>(9, 0.0));
  expect_contains(format_error("frames/0001/particles/2"), {"[4,3]", "[3,3]"});
}

TEST_F(SceneReaderTest, LabelMissingInOneFrame) {
  test::h5_delete(path_, "frames/0003/labels/min_distance");
  expect_contains(format_error("frames/0003/labels/min_distance"), {"missing"});
}

TEST_F(SceneReaderTest, NanLabel) {
  test::h5_put(path_, "frames/0004/labels/min_distance", {}, {std::nan("")});
  expect_contains(format_error("frames/0004/labels/min_distance"), {"non-finite"});
}

TEST_F(SceneReaderTest, LabelThatIsNotAScalar) {
  test::h5_put(path_, "frames/0001/labels/min_distance", {2}, {1, 2});
  expect_contains(format_error("frames/0001/labels/min_distance"), {"single value", "[2]"});
}

}  // namespace
}  // namespace dynscope
