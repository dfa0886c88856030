// Shared helpers of the io tests: temporary directories, a sample scene, raw HDF5 edits.
#pragma once

#include <gtest/gtest.h>
#include <hdf5.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <string>
#include <vector>

#include "engine/core/error.h"
#include "engine/core/rng.h"
#include "engine/scene/scene.h"

namespace dynscope::test {

/// A fresh directory under the system temp dir, removed with everything in it at destruction.
class TempDir {
 public:
  TempDir() {
    static std::atomic<int> counter{0};
    path_ = std::filesystem::temp_directory_path() /
            ("dynscope-io-test-" + std::to_string(getpid()) + "-" + std::to_string(counter++));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  /// Path of `name` inside the directory.
  std::string file(const std::string& name) const { return (path_ / name).string(); }
  /// Names of the entries in the directory.
  std::vector<std::string> entries() const {
    std::vector<std::string> names;
    for (const auto& e : std::filesystem::directory_iterator(path_)) {
      names.push_back(e.path().filename().string());
    }
    return names;
  }

 private:
  std::filesystem::path path_;
};

/// Writes `text` (or bytes) to `path`.
inline void write_text(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

/// The message of the exception of type E that `f` throws; fails the test if it throws nothing
/// or something else.
template <typename E>
std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "threw a different exception: " << e.what();
    return "";
  }
  ADD_FAILURE() << "threw nothing";
  return "";
}

/// Expects `message` to contain every string of `parts`.
inline void expect_contains(const std::string& message, std::initializer_list<std::string> parts) {
  for (const std::string& part : parts) {
    EXPECT_NE(message.find(part), std::string::npos) << "'" << part << "' not in: " << message;
  }
}

/// A unit quaternion drawn from `rng` (normalised Gaussian 4-vector).
inline Quat random_rotation(Rng& rng) {
  Quat q(rng.normal(), rng.normal(), rng.normal(), rng.normal());
  return q.normalized();
}

/// Three objects over 5 frames: a rigid box target, a rigid non-uniformly scaled cylinder zone
/// and a deformable two-triangle sheet, with two labels.
inline Scene make_test_scene() {
  Rng rng(7);
  Scene scene;
  scene.scenario = "drop";
  scene.seed = 0xFFFFFFFFFFFFFFF1ULL;
  scene.dt_s = 1.0 / 24.0;
  Object box;
  box.id = 3;
  box.name = "red box";
  box.role = Role::kTarget;
  box.mesh = make_box_mesh(Vec3(1.0, 0.5, 0.25));
  box.scale = Vec3(1.5, 1.5, 1.5);
  box.mass = 2.5;
  box.friction = 0.8;
  box.restitution = 0.7;
  box.color = Vec3(1.0, 0.0, 0.0);
  Object zone;
  zone.id = 11;
  zone.name = "zone";
  zone.role = Role::kZone;
  zone.mesh = make_cylinder_mesh(0.5, 0.1, 12);
  zone.scale = Vec3(2.0, 3.0, 0.5);
  zone.mass = 0.0;
  zone.color = Vec3(1.0, 1.0, 0.0);
  Object sheet;
  sheet.id = 40;
  sheet.name = "sheet";
  sheet.role = Role::kProbe;
  sheet.rigid = false;
  sheet.mesh.vertices.resize(4, 3);
  sheet.mesh.vertices << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0;
  sheet.mesh.faces.resize(2, 3);
  sheet.mesh.faces << 0, 1, 2, 0, 2, 3;
  scene.objects = {box, zone, sheet};
  scene.trajectories.resize(3);
  const int frames = 5;
  for (int t = 0; t < frames; ++t) {
    for (int i = 0; i < 2; ++i) {
      Pose pose;
      pose.position = Vec3(rng.normal(), rng.normal(), rng.uniform() * 3);
      pose.rotation = random_rotation(rng);
      scene.trajectories[static_cast<size_t>(i)].poses.push_back(pose);
    }
    Points particles = sheet.mesh.vertices;
    for (Eigen::Index r = 0; r < particles.rows(); ++r) particles(r, 2) += 0.1 * rng.normal();
    scene.trajectories[2].particles.push_back(particles);
    scene.labels["target_contacting_zone"].push_back(t >= 3 ? 1.0 : 0.0);
    scene.labels["min_distance"].push_back(1.0 / (t + 1.0) + 1e-17 * t);
  }
  return scene;
}

// Raw HDF5 edits of an existing file (full paths such as "frames/0001/objects/positions").

/// Opens `file` read-write and runs `edit` with the file id.
inline void h5_edit(const std::string& file, const std::function<void(hid_t)>& edit) {
  const hid_t f = H5Fopen(file.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(f, 0) << file;
  edit(f);
  ASSERT_GE(H5Fclose(f), 0);
}

/// Removes the link `path` (a dataset or a whole group).
inline void h5_delete(const std::string& file, const std::string& path) {
  h5_edit(file, [&](hid_t f) { ASSERT_GE(H5Ldelete(f, path.c_str(), H5P_DEFAULT), 0) << path; });
}

/// Creates (or replaces) dataset `path` with `dims` and row-major `values` stored as `type`.
inline void h5_put(hid_t f, const std::string& path, const std::vector<hsize_t>& dims,
                   const std::vector<double>& values, hid_t type = H5T_IEEE_F64LE) {
  if (H5Lexists(f, path.c_str(), H5P_DEFAULT) > 0) H5Ldelete(f, path.c_str(), H5P_DEFAULT);
  const hid_t space = dims.empty()
                          ? H5Screate(H5S_SCALAR)
                          : H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr);
  const hid_t lcpl = H5Pcreate(H5P_LINK_CREATE);
  H5Pset_create_intermediate_group(lcpl, 1);
  const hid_t ds = H5Dcreate2(f, path.c_str(), type, space, lcpl, H5P_DEFAULT, H5P_DEFAULT);
  ASSERT_GE(ds, 0) << path;
  if (!values.empty()) {
    ASSERT_GE(H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()), 0);
  }
  H5Dclose(ds);
  H5Pclose(lcpl);
  H5Sclose(space);
}

/// Same as h5_put for one file path.
inline void h5_put(const std::string& file, const std::string& path,
                   const std::vector<hsize_t>& dims, const std::vector<double>& values,
                   hid_t type = H5T_IEEE_F64LE) {
  h5_edit(file, [&](hid_t f) { h5_put(f, path, dims, values, type); });
}

/// Sets (or replaces) string attribute `name` of the object at `path` ("/" for the root).
inline void h5_set_attribute(const std::string& file, const std::string& path,
                             const std::string& name, const std::string& value) {
  h5_edit(file, [&](hid_t f) {
    if (H5Aexists_by_name(f, path.c_str(), name.c_str(), H5P_DEFAULT) > 0) {
      H5Adelete_by_name(f, path.c_str(), name.c_str(), H5P_DEFAULT);
    }
    const hid_t type = H5Tcopy(H5T_C_S1);
    H5Tset_size(type, H5T_VARIABLE);
    const hid_t space = H5Screate(H5S_SCALAR);
    const hid_t attr = H5Acreate_by_name(f, path.c_str(), name.c_str(), type, space, H5P_DEFAULT,
                                         H5P_DEFAULT, H5P_DEFAULT);
    ASSERT_GE(attr, 0);
    const char* ptr = value.c_str();
    H5Awrite(attr, type, &ptr);
    H5Aclose(attr);
    H5Sclose(space);
    H5Tclose(type);
  });
}

/// Removes attribute `name` of the object at `path`.
inline void h5_delete_attribute(const std::string& file, const std::string& path,
                                const std::string& name) {
  h5_edit(file, [&](hid_t f) {
    ASSERT_GE(H5Adelete_by_name(f, path.c_str(), name.c_str(), H5P_DEFAULT), 0) << name;
  });
}

}  // namespace dynscope::test
