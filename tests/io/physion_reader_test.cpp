// Tests of reading Physion (TDW) HDF5 files: axes, quaternion order, scale, roles, labels.
#include <gtest/gtest.h>

#include <cmath>

#include "engine/io/scene_file.h"
#include "tests/io/io_test_util.h"

namespace dynscope {
namespace {

using test::error_of;
using test::expect_contains;

// Unity/TDW (x, y, z) -> dynscope (x, z, y).
Mat3 physion_axes() {
  Mat3 a;
  a << 1, 0, 0, 0, 0, 1, 0, 1, 0;
  return a;
}

float f32(double v) { return static_cast<float>(v); }

// `m` with every coefficient rounded to float32, as TDW stores it.
template <typename Matrix>
Matrix rounded(const Matrix& m) {
  return m.unaryExpr([](double v) { return static_cast<double>(static_cast<float>(v)); });
}

// What a Physion file holds, in Unity's numbers (rounded to float32 as TDW stores them).
struct PhysionData {
  std::vector<int32_t> ids = {1, 2, 5};
  std::vector<Mesh> meshes;
  std::vector<Vec3> scales;
  std::vector<std::vector<Vec3>> positions;             // [T][O]
  std::vector<std::vector<Eigen::Vector4d>> rotations;  // [T][O], x y z w
  std::vector<bool> contact;                            // [T]
  int frames = 4;
};

PhysionData make_physion_data() {
  Rng rng(3);
  PhysionData d;
  d.meshes = {make_box_mesh(Vec3(1, 1, 1)), make_box_mesh(Vec3(1, 1, 1)),
              make_sphere_mesh(0.5, 4, 6)};
  for (Mesh& m : d.meshes) m.vertices = rounded(m.vertices);
  d.scales = {rounded(Vec3(0.2, 0.4, 0.6)), rounded(Vec3(1.0, 0.05, 1.5)),
              rounded(Vec3(0.3, 0.3, 0.3))};
  for (int t = 0; t < d.frames; ++t) {
    std::vector<Vec3> p;
    std::vector<Eigen::Vector4d> q;
    for (size_t i = 0; i < d.ids.size(); ++i) {
      p.emplace_back(f32(rng.normal()), f32(rng.uniform()), f32(rng.normal()));
      const Quat r = test::random_rotation(rng);
      q.emplace_back(f32(r.x()), f32(r.y()), f32(r.z()), f32(r.w()));
    }
    d.positions.push_back(p);
    d.rotations.push_back(q);
    d.contact.push_back(t == 2);
  }
  return d;
}

// Creates dataset `path` (and missing parent groups, as h5py does); fails the test on error.
hid_t create_dataset(hid_t f, const std::string& path, hid_t type, hid_t space) {
  const hid_t lcpl = H5Pcreate(H5P_LINK_CREATE);
  H5Pset_create_intermediate_group(lcpl, 1);
  const hid_t ds = H5Dcreate2(f, path.c_str(), type, space, lcpl, H5P_DEFAULT, H5P_DEFAULT);
  H5Pclose(lcpl);
  EXPECT_GE(ds, 0) << path;
  return ds;
}

void put_fixed_strings(hid_t f, const std::string& path, const std::vector<std::string>& values) {
  size_t width = 1;
  for (const std::string& v : values) width = std::max(width, v.size());
  const hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, width);
  H5Tset_strpad(type, H5T_STR_NULLPAD);
  std::vector<char> raw(width * values.size(), '\0');
  for (size_t i = 0; i < values.size(); ++i) {
    std::copy(values[i].begin(), values[i].end(), raw.begin() + static_cast<long>(i * width));
  }
  const hsize_t dims[1] = {values.size()};
  const hid_t space = H5Screate_simple(1, dims, nullptr);
  const hid_t ds = create_dataset(f, path, type, space);
  H5Dwrite(ds, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, raw.data());
  H5Dclose(ds);
  H5Sclose(space);
  H5Tclose(type);
}

// h5py stores a numpy bool as an int8 enum {FALSE: 0, TRUE: 1}.
void put_bool(hid_t f, const std::string& path, bool value) {
  const hid_t type = H5Tenum_create(H5T_NATIVE_INT8);
  int8_t v = 0;
  H5Tenum_insert(type, "FALSE", &v);
  v = 1;
  H5Tenum_insert(type, "TRUE", &v);
  const hid_t space = H5Screate(H5S_SCALAR);
  const hid_t ds = create_dataset(f, path, type, space);
  const int8_t b = value ? 1 : 0;
  H5Dwrite(ds, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, &b);
  H5Dclose(ds);
  H5Sclose(space);
  H5Tclose(type);
}

std::vector<double> flat(const std::vector<Vec3>& rows) {
  std::vector<double> out;
  for (const Vec3& r : rows) out.insert(out.end(), {r.x(), r.y(), r.z()});
  return out;
}

struct PhysionOptions {
  bool optional_fields = true;  // mass, friction, names, color, roles, labels
  bool mesh = true;
  bool scale_xyz_only = false;  // older files: scale_x / scale_y / scale_z instead of scale
};

PhysionOptions without_optional_fields() {
  PhysionOptions o;
  o.optional_fields = false;
  return o;
}

PhysionOptions without_mesh() {
  PhysionOptions o;
  o.mesh = false;
  return o;
}

PhysionOptions with_per_axis_scale() {
  PhysionOptions o;
  o.scale_xyz_only = true;
  return o;
}

// Writes `d` the way tdw_physics does (float32 data, xyzw, y up, meshes unscaled).
void write_physion(const std::string& path, const PhysionData& d, const PhysionOptions& opt) {
  const hid_t f = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  H5Gclose(H5Gcreate2(f, "static", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  const hsize_t count = d.ids.size();
  test::h5_put(f, "static/object_ids", {count}, std::vector<double>(d.ids.begin(), d.ids.end()),
               H5T_STD_I32LE);
  if (opt.scale_xyz_only) {
    for (int c = 0; c < 3; ++c) {
      std::vector<double> v;
      for (const Vec3& s : d.scales) v.push_back(s[c]);
      test::h5_put(
          f, std::string("static/scale_") + "xyz" [c], { count }, v, H5T_IEEE_F32LE);
    }
  } else {
    test::h5_put(f, "static/scale", {count, 3}, flat(d.scales), H5T_IEEE_F32LE);
  }
  if (opt.optional_fields) {
    test::h5_put(f, "static/mass", {count}, {1.5, 0.0, 0.25}, H5T_IEEE_F32LE);
    test::h5_put(f, "static/static_friction", {count}, {0.1, 0.2, 0.3}, H5T_IEEE_F32LE);
    test::h5_put(f, "static/dynamic_friction", {count}, {0.9, 0.9, 0.9}, H5T_IEEE_F32LE);
    test::h5_put(f, "static/bounciness", {count}, {0.4, 0.5, 0.6}, H5T_IEEE_F32LE);
    test::h5_put(f, "static/color", {count, 3}, {1, 0, 0, 1, 1, 0, 0.5, 0.5, 0.5}, H5T_IEEE_F32LE);
    test::h5_put(f, "static/target_id", {}, {1}, H5T_STD_I64LE);
    test::h5_put(f, "static/zone_id", {}, {2}, H5T_STD_I64LE);
    put_fixed_strings(f, "static/model_names", {"cube", "zone_box", "sphere"});
    put_fixed_strings(f, "static/stimulus_name", {"pilot_it2_drop_0001"});
  }
  if (opt.mesh) {
    for (size_t i = 0; i < d.meshes.size(); ++i) {
      const Mesh& m = d.meshes[i];
      const auto v = static_cast<hsize_t>(m.num_vertices());
      const auto fc = static_cast<hsize_t>(m.num_faces());
      test::h5_put(f, "static/mesh/vertices_" + std::to_string(i), {v, 3},
                   std::vector<double>(m.vertices.data(), m.vertices.data() + 3 * v),
                   H5T_IEEE_F32LE);
      test::h5_put(f, "static/mesh/faces_" + std::to_string(i), {fc, 3},
                   std::vector<double>(m.faces.data(), m.faces.data() + 3 * fc), H5T_STD_I32LE);
    }
  }
  for (int t = 0; t < d.frames; ++t) {
    char name[32];
    std::snprintf(name, sizeof name, "frames/%04d", t);
    const std::string frame = name;
    std::vector<double> q;
    for (const Eigen::Vector4d& r : d.rotations[static_cast<size_t>(t)]) {
      q.insert(q.end(), {r[0], r[1], r[2], r[3]});
    }
    test::h5_put(f, frame + "/objects/positions", {count, 3},
                 flat(d.positions[static_cast<size_t>(t)]), H5T_IEEE_F32LE);
    test::h5_put(f, frame + "/objects/rotations", {count, 4}, q, H5T_IEEE_F32LE);
    test::h5_put(f, frame + "/objects/velocities", {count, 3}, std::vector<double>(9, 0.0),
                 H5T_IEEE_F32LE);
    test::h5_put(f, frame + "/images/_img", {16}, std::vector<double>(16, 7.0), H5T_STD_U8LE);
    if (opt.optional_fields) {
      put_bool(f, frame + "/labels/target_contacting_zone", d.contact[static_cast<size_t>(t)]);
      test::h5_put(f, frame + "/labels/minimum_distance_target_to_zone", {}, {0.5 - 0.1 * t},
                   H5T_IEEE_F32LE);
      test::h5_put(f, frame + "/labels/contact_points", {2}, {1.0, 2.0}, H5T_IEEE_F32LE);
      if (t > 0) test::h5_put(f, frame + "/labels/late_label", {}, {1.0});
      test::h5_put(f, frame + "/labels/sometimes_nan", {}, {t == 1 ? std::nan("") : 1.0});
    }
  }
  ASSERT_GE(H5Fclose(f), 0);
}

// World position of vertex j of object i at frame t as Physion computes it (Unity numbers).
Vec3 physion_world_vertex(const PhysionData& d, size_t i, int t, Eigen::Index j) {
  const Eigen::Vector4d q = d.rotations[static_cast<size_t>(t)][i];
  const Quat r = Quat(q[3], q[0], q[1], q[2]).normalized();
  const Vec3 v = d.meshes[i].vertices.row(j).transpose();
  return r * d.scales[i].cwiseProduct(v) + d.positions[static_cast<size_t>(t)][i];
}

class PhysionReaderTest : public ::testing::Test {
 protected:
  test::TempDir dir_;
  PhysionData data_ = make_physion_data();
  std::string path_ = dir_.file("pilot_it2_drop_0001.hdf5");
};

TEST_F(PhysionReaderTest, ConvertsAxesQuaternionOrderAndScale) {
  write_physion(path_, data_, {});
  const Scene scene = read_scene(path_);
  const Mat3 a = physion_axes();
  ASSERT_EQ(scene.objects.size(), 3u);
  ASSERT_EQ(scene.num_frames(), data_.frames);
  EXPECT_EQ(scene.scenario, "physion");
  EXPECT_DOUBLE_EQ(scene.dt_s, 0.01);
  for (size_t i = 0; i < 3; ++i) {
    const Object& o = scene.objects[i];
    EXPECT_EQ(o.id, data_.ids[i]);
    // Scale is permuted with the axes; the mesh stays unscaled.
    const Vec3& s = data_.scales[i];
    EXPECT_EQ(o.scale, Vec3(s.x(), s.z(), s.y()));
    EXPECT_EQ(o.mesh.num_vertices(), data_.meshes[i].num_vertices());
    for (int t = 0; t < data_.frames; ++t) {
      const Points world = scene.world_vertices(static_cast<int>(i), t);
      for (Eigen::Index j = 0; j < world.rows(); ++j) {
        const Vec3 expected = a * physion_world_vertex(data_, i, t, j);
        EXPECT_LT((world.row(j).transpose() - expected).norm(), 1e-6)
            << "object " << i << " frame " << t << " vertex " << j;
      }
      // Rotations become A R Aᵀ: proper rotations again (det +1).
      const Mat3 r =
          scene.trajectories[i].poses[static_cast<size_t>(t)].rotation.toRotationMatrix();
      EXPECT_NEAR(r.determinant(), 1.0, 1e-9);
      const Eigen::Vector4d q = data_.rotations[static_cast<size_t>(t)][i];
      const Mat3 ru = Quat(q[3], q[0], q[1], q[2]).normalized().toRotationMatrix();
      EXPECT_LT((r - a * ru * a.transpose()).norm(), 1e-9);
    }
  }
}

TEST_F(PhysionReaderTest, KeepsTrianglesFacingOutwardAfterTheReflection) {
  write_physion(path_, data_, {});
  const Scene scene = read_scene(path_);
  for (int i : {0, 2}) {
    const Points world = scene.world_vertices(i, 1);
    const Vec3 centre = world.colwise().mean().transpose();
    const Faces& faces = scene.objects[static_cast<size_t>(i)].mesh.faces;
    for (Eigen::Index f = 0; f < faces.rows(); ++f) {
      const Vec3 a = world.row(faces(f, 0)).transpose();
      const Vec3 b = world.row(faces(f, 1)).transpose();
      const Vec3 c = world.row(faces(f, 2)).transpose();
      EXPECT_GT((b - a).cross(c - a).dot((a + b + c) / 3 - centre), 0.0)
          << "object " << i << " face " << f;
    }
  }
}

TEST_F(PhysionReaderTest, ReadsRolesMaterialsNamesAndLabels) {
  write_physion(path_, data_, {});
  const Scene scene = read_physion(path_);
  EXPECT_EQ(scene.objects[0].role, Role::kTarget);
  EXPECT_EQ(scene.objects[1].role, Role::kZone);
  EXPECT_EQ(scene.objects[2].role, Role::kOther);
  EXPECT_EQ(scene.objects[1].name, "zone_box");
  EXPECT_EQ(scene.objects[2].name, "sphere");
  EXPECT_EQ(scene.objects[0].mass, 1.5);
  EXPECT_EQ(scene.objects[1].friction, f32(0.2));
  EXPECT_EQ(scene.objects[2].restitution, f32(0.6));
  EXPECT_EQ(scene.objects[1].color, Vec3(1, 1, 0));
  ASSERT_EQ(scene.labels.count("target_contacting_zone"), 1u);
  EXPECT_EQ(scene.labels.at("target_contacting_zone"), (std::vector<double>{0, 0, 1, 0}));
  EXPECT_NEAR(scene.labels.at("minimum_distance_target_to_zone")[3], 0.2, 1e-6);
  // Non-scalar labels and labels missing or NaN in some frames are skipped, not errors.
  EXPECT_EQ(scene.labels.count("contact_points"), 0u);
  EXPECT_EQ(scene.labels.count("late_label"), 0u);
  EXPECT_EQ(scene.labels.count("sometimes_nan"), 0u);
}

TEST_F(PhysionReaderTest, RootDtAttributeOverridesTheDefault) {
  write_physion(path_, data_, {});
  test::h5_edit(path_, [](hid_t f) {
    const double dt = 1.0 / 30.0;
    const hid_t space = H5Screate(H5S_SCALAR);
    const hid_t attr = H5Acreate2(f, "dt", H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT);
    H5Awrite(attr, H5T_NATIVE_DOUBLE, &dt);
    H5Aclose(attr);
    H5Sclose(space);
  });
  EXPECT_DOUBLE_EQ(read_scene(path_).dt_s, 1.0 / 30.0);
}

TEST_F(PhysionReaderTest, ToleratesMissingOptionalGroups) {
  write_physion(path_, data_, without_optional_fields());
  const Scene scene = read_scene(path_);
  const Object defaults;
  EXPECT_EQ(scene.objects[0].name, "object_1");
  EXPECT_EQ(scene.objects[0].role, Role::kOther);
  EXPECT_EQ(scene.objects[0].mass, defaults.mass);
  EXPECT_EQ(scene.objects[0].friction, defaults.friction);
  EXPECT_EQ(scene.objects[0].color, defaults.color);
  EXPECT_TRUE(scene.labels.empty());
  EXPECT_EQ(scene.find_role(Role::kTarget), -1);
}

TEST_F(PhysionReaderTest, ReadsPerAxisScaleDatasets) {
  write_physion(path_, data_, with_per_axis_scale());
  const Scene scene = read_scene(path_);
  const Vec3& s = data_.scales[1];
  EXPECT_EQ(scene.objects[1].scale, Vec3(s.x(), s.z(), s.y()));
}

TEST_F(PhysionReaderTest, MissingMeshesAreAFormatError) {
  write_physion(path_, data_, without_mesh());
  expect_contains(error_of<FormatError>([&] { read_scene(path_); }),
                  {path_ + ": static/mesh", "missing group"});
}

TEST_F(PhysionReaderTest, ZoneIdThatIsNotAnObjectIsAFormatError) {
  write_physion(path_, data_, {});
  test::h5_put(path_, "static/zone_id", {}, {77}, H5T_STD_I64LE);
  expect_contains(error_of<FormatError>([&] { read_scene(path_); }),
                  {path_ + ": static/zone_id", "77"});
}

TEST_F(PhysionReaderTest, MismatchedObjectCountsAreAFormatError) {
  write_physion(path_, data_, {});
  test::h5_put(path_, "frames/0001/objects/rotations", {2, 4}, std::vector<double>(8, 0.5),
               H5T_IEEE_F32LE);
  expect_contains(
      error_of<FormatError>([&] { read_scene(path_); }),
      {path_ + ": frames/0001/objects/rotations", "expected [3,4]", "got [2,4] float32"});
}

}  // namespace
}  // namespace dynscope
