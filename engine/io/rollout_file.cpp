// Rollout file writer and reader (layout in rollout_file.h).
#include "engine/io/rollout_file.h"

#include <cmath>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include "engine/core/error.h"
#include "engine/io/h5_util.h"
#include "engine/io/scene_file.h"
#include "engine/io/temp_file.h"

namespace dynscope {

namespace {

// Writes a rank-3 float64 dataset (Group's public writers stop at rank 2).
void write_tensor3(const h5::Group& g, const std::string& name, const std::vector<double>& data,
                   hsize_t d0, hsize_t d1, hsize_t d2) {
  const hsize_t dims[3] = {d0, d1, d2};
  h5::Handle space(H5Screate_simple(3, dims, nullptr));
  h5::Handle ds(H5Dcreate2(g.id(), name.c_str(), H5T_IEEE_F64LE, space.get(), H5P_DEFAULT,
                           H5P_DEFAULT, H5P_DEFAULT));
  if (!space.valid() || !ds.valid()) {
    throw IoError(g.file(), g.child_path(name) + ": cannot create dataset");
  }
  if (!data.empty() &&
      H5Dwrite(ds.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, data.data()) < 0) {
    throw IoError(g.file(), g.child_path(name) + ": write failed");
  }
}

// Reads a numeric rank-3 dataset of shape [d0,d1,d2] (−1: any) as doubles; the first extent goes
// to `d0_out` when given.
std::vector<double> read_tensor3(const h5::Group& g, const std::string& name, int64_t d0,
                                 int64_t d1, int64_t d2, int64_t* d0_out = nullptr) {
  h5::Shape s;
  std::vector<double> out = g.read_array(name, {d0, d1, d2}, &s);
  if (d0_out != nullptr) *d0_out = static_cast<int64_t>(s.dims[0]);
  return out;
}

std::vector<double> flatten(const std::vector<Points>& frames) {
  std::vector<double> out;
  for (const Points& p : frames) out.insert(out.end(), p.data(), p.data() + p.size());
  return out;
}

std::vector<Points> unflatten(const std::vector<double>& data, int64_t t, int64_t n) {
  std::vector<Points> out;
  out.reserve(static_cast<size_t>(t));
  for (int64_t f = 0; f < t; ++f) {
    out.push_back(Eigen::Map<const Points>(data.data() + f * n * 3, n, 3));
  }
  return out;
}

std::string required_string(const h5::Group& root, const char* name) {
  const auto v = root.string_attribute(name);
  if (!v) throw FormatError(root.file(), std::string("@") + name, "missing attribute");
  return *v;
}

template <typename T>
std::vector<T> narrow_ints(const std::vector<int64_t>& v) {
  return std::vector<T>(v.begin(), v.end());
}

void require_finite(const std::vector<double>& v, const std::string& path,
                    const std::string& field) {
  for (size_t i = 0; i < v.size(); ++i) {
    if (!std::isfinite(v[i]) || v[i] < 0) {
      throw FormatError(path, field,
                        "value " + std::to_string(v[i]) + " at frame " + std::to_string(i) +
                            " is not a finite distance >= 0");
    }
  }
}

// What Rollout::validate does not cover: metrics and poses are finite, rotations are unit
// quaternions, every point's object has a pose, and the sampling voxel is a length.
void validate_read_values(const Rollout& r, const std::string& path) {
  require_finite(r.point_error, path, "metrics/point_error");
  require_finite(r.contact_distance_truth, path, "metrics/contact_distance_truth");
  require_finite(r.contact_distance_predicted, path, "metrics/contact_distance_predicted");
  if (!std::isfinite(r.sampling_voxel) || r.sampling_voxel < 0) {
    throw FormatError(path, "@sampling_voxel", "must be a finite length >= 0");
  }
  for (size_t f = 0; f < r.poses.size(); ++f) {
    for (size_t j = 0; j < r.poses[f].size(); ++j) {
      const Pose& p = r.poses[f][j];
      if (!p.position.allFinite() || !p.rotation.coeffs().allFinite() ||
          std::abs(p.rotation.norm() - 1.0) > 1e-3) {
        throw FormatError(path, "poses/fitted",
                          "pose of object " + std::to_string(j) + " at frame " + std::to_string(f) +
                              " is not finite with a unit quaternion");
      }
    }
  }
  const std::set<int32_t> posed(r.pose_object_ids.begin(), r.pose_object_ids.end());
  for (size_t i = 0; i < r.object_ids.size(); ++i) {
    if (posed.count(r.object_ids[i]) == 0) {
      throw FormatError(path, "points/object_ids",
                        "object " + std::to_string(r.object_ids[i]) + " of point " +
                            std::to_string(i) + " is not in poses/object_ids");
    }
  }
}

}  // namespace

void write_rollout(const Rollout& r, const std::string& path) {
  h5::silence_errors();
  r.validate();
  const auto t = static_cast<hsize_t>(r.num_frames());
  const auto n = static_cast<hsize_t>(r.num_points());
  const auto o = static_cast<hsize_t>(r.num_objects());
  TempFile temp(path);
  {
    h5::Group root = h5::Group::create_file(temp.path());
    root.write_attribute("format", std::string(kRolloutFormatName));
    root.write_attribute("format_version", kRolloutFormatVersion);
    root.write_attribute("up_axis", std::string("z"));
    root.write_attribute("quaternion_order", std::string("wxyz"));
    root.write_attribute("scene_path", r.scene_path);
    root.write_attribute("checkpoint_path", r.checkpoint_path);
    root.write_attribute("model_config", r.model_config);
    root.write_attribute("scenario", r.scenario);
    root.write_attribute("dt", r.dt_s);
    root.write_attribute("observed_frames", static_cast<int64_t>(r.observed_frames));
    root.write_attribute("sampling_voxel", r.sampling_voxel);
    root.write_attribute("num_frames", static_cast<int64_t>(t));
    root.write_attribute("num_points", static_cast<int64_t>(n));

    const h5::Group points = root.create_group("points");
    points.write_matrix("rest", r.rest.data(), n, 3);
    points.write_int_vector("object_ids", r.object_ids);
    if (!r.static_points.empty()) points.write_uint8_vector("static", r.static_points);
    if (r.faces.rows() > 0) {
      points.write_int_matrix("faces", r.faces.data(), static_cast<hsize_t>(r.faces.rows()), 3);
    }

    const h5::Group positions = root.create_group("positions");
    write_tensor3(positions, "predicted", flatten(r.predicted), t, n, 3);
    write_tensor3(positions, "truth", flatten(r.truth), t, n, 3);

    const h5::Group poses = root.create_group("poses");
    poses.write_int_vector("object_ids", r.pose_object_ids);
    poses.write_uint8_vector("rigid", r.pose_rigid);
    std::vector<double> fitted;
    fitted.reserve(static_cast<size_t>(t * o * 7));
    for (const auto& frame : r.poses) {
      for (const Pose& p : frame) {
        fitted.insert(fitted.end(), {p.position.x(), p.position.y(), p.position.z(), p.rotation.w(),
                                     p.rotation.x(), p.rotation.y(), p.rotation.z()});
      }
    }
    write_tensor3(poses, "fitted", fitted, t, o, 7);

    const h5::Group metrics = root.create_group("metrics");
    metrics.write_vector("point_error", r.point_error);
    if (r.has_contact()) {
      metrics.write_vector("contact_distance_truth", r.contact_distance_truth);
      metrics.write_vector("contact_distance_predicted", r.contact_distance_predicted);
    }
    root.close();
  }
  temp.commit();
}

Rollout read_rollout(const std::string& path) {
  h5::silence_errors();
  const h5::Group root = h5::Group::open_file(path);
  const std::string format = required_string(root, "format");
  if (format != kRolloutFormatName) {
    throw FormatError(path, "@format",
                      "is '" + format + "', expected '" + kRolloutFormatName + "'");
  }
  const auto version = root.int_attribute("format_version");
  if (!version || *version < 1 || *version > kRolloutFormatVersion) {
    throw FormatError(path, "@format_version",
                      version ? "unsupported version " + std::to_string(*version) : "missing");
  }
  if (root.string_attribute("quaternion_order").value_or("") != "wxyz") {
    throw FormatError(path, "@quaternion_order", "expected 'wxyz'");
  }
  Rollout r;
  r.scene_path = required_string(root, "scene_path");
  r.checkpoint_path = required_string(root, "checkpoint_path");
  r.model_config = required_string(root, "model_config");
  r.scenario = required_string(root, "scenario");
  r.dt_s = root.double_attribute("dt").value_or(0.0);
  r.observed_frames = static_cast<int>(root.int_attribute("observed_frames").value_or(-1));
  r.sampling_voxel = root.double_attribute("sampling_voxel").value_or(0.0);

  const h5::Group points = root.group("points");
  r.rest = points.read_matrix("rest", -1, 3);
  const int64_t n = r.rest.rows();
  r.object_ids = narrow_ints<int32_t>(points.read_int_vector("object_ids", n));
  if (points.has_dataset("faces")) r.faces = points.read_int_matrix("faces", -1, 3).cast<int32_t>();
  if (points.has_dataset("static")) {
    const std::vector<int64_t> flags = points.read_int_vector("static", n);
    for (size_t i = 0; i < flags.size(); ++i) {
      if (flags[i] != 0 && flags[i] != 1) {
        throw FormatError(path, "points/static",
                          "value " + std::to_string(flags[i]) + " of point " + std::to_string(i) +
                              " is not 0 or 1");
      }
    }
    r.static_points = narrow_ints<uint8_t>(flags);
  }

  const h5::Group positions = root.group("positions");
  int64_t t = 0;
  const std::vector<double> predicted = read_tensor3(positions, "predicted", -1, n, 3, &t);
  r.predicted = unflatten(predicted, t, n);
  r.truth = unflatten(read_tensor3(positions, "truth", t, n, 3), t, n);

  const h5::Group poses = root.group("poses");
  r.pose_object_ids = narrow_ints<int32_t>(poses.read_int_vector("object_ids", -1));
  const auto o = static_cast<int64_t>(r.pose_object_ids.size());
  r.pose_rigid = narrow_ints<uint8_t>(poses.read_int_vector("rigid", o));
  const std::vector<double> fitted = read_tensor3(poses, "fitted", t, o, 7);
  r.poses.assign(static_cast<size_t>(t), std::vector<Pose>(static_cast<size_t>(o)));
  for (int64_t f = 0; f < t; ++f) {
    for (int64_t j = 0; j < o; ++j) {
      const double* v = fitted.data() + (f * o + j) * 7;
      Pose& p = r.poses[static_cast<size_t>(f)][static_cast<size_t>(j)];
      p.position = Vec3(v[0], v[1], v[2]);
      p.rotation = Quat(v[3], v[4], v[5], v[6]);
    }
  }

  const h5::Group metrics = root.group("metrics");
  r.point_error = metrics.read_vector("point_error", t);
  if (metrics.has_dataset("contact_distance_truth")) {
    r.contact_distance_truth = metrics.read_vector("contact_distance_truth", t);
    r.contact_distance_predicted = metrics.read_vector("contact_distance_predicted", t);
  }
  try {
    r.validate();
  } catch (const ValueError& e) {
    throw FormatError(path, e.name(), e.what());
  }
  validate_read_values(r, path);
  return r;
}

bool is_rollout_file(const std::string& path) {
  if (!is_hdf5_file(path)) return false;
  h5::silence_errors();
  try {
    const h5::Group root = h5::Group::open_file(path);
    return root.string_attribute("format").value_or("") == kRolloutFormatName;
  } catch (const Error&) {
    return false;
  }
}

std::string find_rollout_scene(const Rollout& rollout, const std::string& rollout_path) {
  namespace fs = std::filesystem;
  if (rollout.scene_path.empty()) return "";
  for (const fs::path& candidate :
       {fs::path(rollout.scene_path),
        fs::path(rollout_path).parent_path() / fs::path(rollout.scene_path).filename()}) {
    std::error_code ec;
    if (fs::is_regular_file(candidate, ec)) return candidate.string();
  }
  return "";
}

}  // namespace dynscope
