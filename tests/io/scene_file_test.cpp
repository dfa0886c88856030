// Tests of the dynscope scene writer and read_scene: exact round trip, atomic writes, detection.
#include "engine/io/scene_file.h"

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <thread>

#include "engine/io/h5_util.h"
#include "tests/io/io_test_util.h"

namespace dynscope {
namespace {

using test::error_of;
using test::expect_contains;
using test::TempDir;

void expect_same_scene(const Scene& a, const Scene& b) {
  EXPECT_EQ(a.scenario, b.scenario);
  EXPECT_EQ(a.seed, b.seed);
  EXPECT_EQ(a.dt_s, b.dt_s);
  ASSERT_EQ(a.objects.size(), b.objects.size());
  ASSERT_EQ(a.num_frames(), b.num_frames());
  for (size_t i = 0; i < a.objects.size(); ++i) {
    const Object& x = a.objects[i];
    const Object& y = b.objects[i];
    EXPECT_EQ(x.id, y.id);
    EXPECT_EQ(x.name, y.name);
    EXPECT_EQ(x.role, y.role);
    EXPECT_EQ(x.rigid, y.rigid);
    EXPECT_EQ(x.mesh.vertices, y.mesh.vertices);
    EXPECT_EQ(x.mesh.faces, y.mesh.faces);
    EXPECT_EQ(x.scale, y.scale);
    EXPECT_EQ(x.mass, y.mass);
    EXPECT_EQ(x.friction, y.friction);
    EXPECT_EQ(x.restitution, y.restitution);
    EXPECT_EQ(x.color, y.color);
    const Trajectory& s = a.trajectories[i];
    const Trajectory& t = b.trajectories[i];
    ASSERT_EQ(s.poses.size(), t.poses.size());
    for (size_t f = 0; f < s.poses.size(); ++f) {
      EXPECT_EQ(s.poses[f].position, t.poses[f].position);
      EXPECT_EQ(s.poses[f].rotation.coeffs(), t.poses[f].rotation.coeffs());
    }
    ASSERT_EQ(s.particles.size(), t.particles.size());
    for (size_t f = 0; f < s.particles.size(); ++f) EXPECT_EQ(s.particles[f], t.particles[f]);
  }
  EXPECT_EQ(a.labels, b.labels);
}

TEST(SceneFile, WriteThenReadIsExact) {
  TempDir dir;
  const Scene scene = test::make_test_scene();
  const std::string path = dir.file("scene.h5");
  write_scene(scene, path);
  const Scene back = read_scene(path);
  expect_same_scene(scene, back);
  EXPECT_EQ(back.objects[2].rigid, false);
  EXPECT_TRUE(back.trajectories[2].poses.empty());
}

std::string file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

TEST(SceneFile, SameSceneGivesByteIdenticalFiles) {
  TempDir dir;
  const Scene scene = test::make_test_scene();
  write_scene(scene, dir.file("a.h5"));
  // HDF5 stamps objects with seconds-resolution times unless told not to; cross a second.
  std::this_thread::sleep_for(std::chrono::milliseconds(1100));
  write_scene(scene, dir.file("b.h5"));
  const std::string a = file_bytes(dir.file("a.h5"));
  EXPECT_FALSE(a.empty());
  EXPECT_TRUE(a == file_bytes(dir.file("b.h5")));
}

TEST(SceneFile, WritesTheDocumentedLayout) {
  TempDir dir;
  const Scene scene = test::make_test_scene();
  const std::string path = dir.file("scene.h5");
  write_scene(scene, path);
  const h5::Group root = h5::Group::open_file(path);
  EXPECT_EQ(root.string_attribute("format"), "dynscope-scene");
  EXPECT_EQ(root.int_attribute("format_version"), 1);
  EXPECT_EQ(root.string_attribute("up_axis"), "z");
  EXPECT_EQ(root.string_attribute("quaternion_order"), "wxyz");
  EXPECT_EQ(root.int_attribute("num_frames"), 5);
  EXPECT_EQ(root.uint_attribute("seed"), scene.seed);
  const h5::Group statics = root.group("static");
  EXPECT_EQ(statics.read_int_scalar("target_id"), 3);
  EXPECT_EQ(statics.read_int_scalar("zone_id"), 11);
  EXPECT_EQ(statics.read_strings("roles", 3),
            (std::vector<std::string>{"target", "zone", "probe"}));
  EXPECT_EQ(statics.read_int_vector("rigid", 3), (std::vector<int64_t>{1, 1, 0}));
  EXPECT_EQ(statics.shape("scale").text(), "[3,3] float64");
  EXPECT_EQ(statics.group("mesh").shape("faces_0").text(), "[12,3] int32");
  const h5::Group frame = root.group("frames").group("0004");
  const h5::MatrixXdR rot = frame.group("objects").read_matrix("rotations", 3, 4);
  const Quat q = scene.trajectories[1].poses[4].rotation;
  EXPECT_EQ(rot(1, 0), q.w());
  EXPECT_EQ(rot(1, 1), q.x());
  EXPECT_EQ(rot(1, 3), q.z());
  // A deformable object's row holds the identity and its particle centroid.
  EXPECT_EQ(rot(2, 0), 1.0);
  const h5::MatrixXdR pos = frame.group("objects").read_matrix("positions", 3, 3);
  const Points& particles = scene.trajectories[2].particles[4];
  EXPECT_NEAR(pos(2, 2), particles.col(2).mean(), 1e-15);
  EXPECT_EQ(frame.group("particles").read_matrix("2", 4, 3), h5::MatrixXdR(particles));
  EXPECT_EQ(frame.group("labels").read_scalar("target_contacting_zone"), 1.0);
}

TEST(SceneFile, EmptySceneRoundTrips) {
  TempDir dir;
  Scene scene;
  scene.scenario = "empty";
  write_scene(scene, dir.file("empty.h5"));
  const Scene back = read_scene(dir.file("empty.h5"));
  EXPECT_EQ(back.scenario, "empty");
  EXPECT_TRUE(back.objects.empty());
  EXPECT_EQ(back.num_frames(), 0);
}

TEST(SceneFile, ReadsXyzwQuaternionOrderWhenDeclared) {
  TempDir dir;
  const Scene scene = test::make_test_scene();
  const std::string path = dir.file("scene.h5");
  write_scene(scene, path);
  // Rewrite frame 0's rotations in x y z w order and declare it.
  const h5::MatrixXdR rot =
      h5::Group::open_file(path).group("frames").group("0000").group("objects").read_matrix(
          "rotations", 3, 4);
  h5::MatrixXdR xyzw(3, 4);
  xyzw << rot.rightCols(3), rot.col(0);
  test::h5_put(path, "frames/0000/objects/rotations", {3, 4},
               std::vector<double>(xyzw.data(), xyzw.data() + xyzw.size()));
  for (int t = 1; t < 5; ++t) test::h5_delete(path, "frames/000" + std::to_string(t));
  test::h5_edit(path, [](hid_t f) { H5Adelete(f, "num_frames"); });
  test::h5_set_attribute(path, "/", "quaternion_order", "xyzw");
  const Scene back = read_scene(path);
  ASSERT_EQ(back.num_frames(), 1);
  EXPECT_EQ(back.trajectories[0].poses[0].rotation.coeffs(),
            scene.trajectories[0].poses[0].rotation.coeffs());
}

TEST(SceneFile, InvalidSceneIsRejectedAndLeavesTheOldFileAlone) {
  TempDir dir;
  const std::string path = dir.file("scene.h5");
  const Scene good = test::make_test_scene();
  write_scene(good, path);
  const auto size_before = std::filesystem::file_size(path);
  Scene bad = good;
  bad.trajectories[0].poses[2].position.x() = std::nan("");
  error_of<ValueError>([&] { write_scene(bad, path); });
  Scene bad_label = good;
  bad_label.labels["a/b"] = std::vector<double>(5, 0.0);
  expect_contains(error_of<ValueError>([&] { write_scene(bad_label, path); }), {"a/b"});
  EXPECT_EQ(std::filesystem::file_size(path), size_before);
  expect_same_scene(good, read_scene(path));
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"scene.h5"}) << "temporary file left over";
}

TEST(SceneFile, OverwritesAtomicallyAndLeavesNoTemporaryFile) {
  TempDir dir;
  const std::string path = dir.file("scene.h5");
  Scene scene = test::make_test_scene();
  write_scene(scene, path);
  scene.scenario = "second";
  write_scene(scene, path);
  EXPECT_EQ(read_scene(path).scenario, "second");
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"scene.h5"});
  EXPECT_EQ(std::filesystem::status(path).permissions() & std::filesystem::perms::others_read,
            std::filesystem::perms::others_read);
}

TEST(SceneFile, UnwritableDirectoryThrowsIoErrorNamingThePath) {
  TempDir dir;
  const std::string path = dir.file("missing-dir/scene.h5");
  expect_contains(error_of<IoError>([&] { write_scene(test::make_test_scene(), path); }), {path});
}

TEST(SceneFile, DetectsHdf5BySignature) {
  TempDir dir;
  write_scene(test::make_test_scene(), dir.file("scene.h5"));
  test::write_text(dir.file("text.h5"), "just text, not HDF5");
  test::write_text(dir.file("short.h5"), "\x89HD");
  EXPECT_TRUE(is_hdf5_file(dir.file("scene.h5")));
  EXPECT_FALSE(is_hdf5_file(dir.file("text.h5")));
  EXPECT_FALSE(is_hdf5_file(dir.file("short.h5")));
  EXPECT_FALSE(is_hdf5_file(dir.file("absent.h5")));
}

TEST(SceneFile, RejectsAFileWithOnlyOneConventionAttribute) {
  TempDir dir;
  const std::string path = dir.file("scene.h5");
  write_scene(test::make_test_scene(), path);
  test::h5_delete_attribute(path, "/", "quaternion_order");
  expect_contains(error_of<FormatError>([&] { read_scene(path); }), {path, "@quaternion_order"});
}

TEST(SceneFile, RejectsUnsupportedConventionsAndVersions) {
  TempDir dir;
  const std::string path = dir.file("scene.h5");
  write_scene(test::make_test_scene(), path);
  test::h5_set_attribute(path, "/", "up_axis", "y");
  expect_contains(error_of<FormatError>([&] { read_scene(path); }), {path, "@up_axis", "'y'"});
  test::h5_set_attribute(path, "/", "up_axis", "z");
  test::h5_set_attribute(path, "/", "quaternion_order", "wzyx");
  expect_contains(error_of<FormatError>([&] { read_scene(path); }), {"@quaternion_order"});
  test::h5_set_attribute(path, "/", "quaternion_order", "wxyz");
  test::h5_set_attribute(path, "/", "format", "something-else");
  expect_contains(error_of<FormatError>([&] { read_scene(path); }), {"@format"});
  test::h5_delete_attribute(path, "/", "format");
  test::h5_edit(path, [](hid_t f) {
    H5Adelete(f, "format_version");
    const int64_t v = 2;
    const hid_t space = H5Screate(H5S_SCALAR);
    const hid_t a = H5Acreate2(f, "format_version", H5T_STD_I64LE, space, H5P_DEFAULT, H5P_DEFAULT);
    H5Awrite(a, H5T_NATIVE_INT64, &v);
    H5Aclose(a);
    H5Sclose(space);
  });
  expect_contains(error_of<FormatError>([&] { read_scene(path); }), {"@format_version", "2"});
}

}  // namespace
}  // namespace dynscope
