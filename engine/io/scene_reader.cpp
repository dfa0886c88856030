// The shared scene-file reader: static object data, per-frame poses/particles/labels, axes.
#include "engine/io/scene_reader.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <set>

#include "engine/core/error.h"
#include "engine/core/log.h"

namespace dynscope {
namespace {

using h5::Group;
using h5::MatrixXdR;

// A quaternion whose norm is this far from 1 is renormalised (Physion stores float32);
// well-formed double files stay bit-exact.
constexpr double kUnitTolerance = 1e-9;
constexpr double kMinQuaternionNorm = 1e-6;

std::string frame_name(int frame) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "%04d", frame);
  return buf;
}

// Largest magnitude of any stored number (coordinates, scales, masses): scenes are metre-like,
// and values near the double range overflow bounds, grids and cameras downstream.
constexpr double kMaxMagnitude = 1e7;

bool in_bounds(double v) { return std::isfinite(v) && std::abs(v) <= kMaxMagnitude; }

void require_finite(const MatrixXdR& m, const Group& g, const std::string& name) {
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    for (Eigen::Index c = 0; c < m.cols(); ++c) {
      if (!in_bounds(m(r, c))) {
        throw FormatError(g.file(), g.child_path(name),
                          "non-finite or out-of-range value " + std::to_string(m(r, c)) +
                              " in row " + std::to_string(r) + " (accepted: finite, within +-1e7)");
      }
    }
  }
}

void require_finite(const std::vector<double>& v, const Group& g, const std::string& name) {
  for (size_t i = 0; i < v.size(); ++i) {
    if (!in_bounds(v[i])) {
      throw FormatError(g.file(), g.child_path(name),
                        "non-finite or out-of-range value " + std::to_string(v[i]) + " at index " +
                            std::to_string(i) + " (accepted: finite, within +-1e7)");
    }
  }
}

// Physical parameters: masses, friction and restitution coefficients are never negative.
void require_non_negative(const std::vector<double>& v, const Group& g, const char* name) {
  for (size_t i = 0; i < v.size(); ++i) {
    if (v[i] < 0) {
      throw FormatError(
          g.file(), g.child_path(name),
          "must be >= 0, got " + std::to_string(v[i]) + " at index " + std::to_string(i));
    }
  }
}

// Optional per-object `[O]` numbers: the first present name wins, else `fallback` everywhere.
std::vector<double> optional_vector(const Group& g, std::initializer_list<const char*> names,
                                    size_t count, double fallback) {
  for (const char* name : names) {
    if (g.has(name)) {
      std::vector<double> v = g.read_vector(name, static_cast<int64_t>(count));
      require_finite(v, g, name);
      return v;
    }
  }
  return std::vector<double>(count, fallback);
}

// Optional per-object `[O,3]` numbers, as rows of Vec3.
std::vector<Vec3> optional_vec3(const Group& g, const char* name, size_t count,
                                const Vec3& fallback) {
  std::vector<Vec3> out(count, fallback);
  if (!g.has(name)) return out;
  const MatrixXdR m = g.read_matrix(name, static_cast<int64_t>(count), 3);
  require_finite(m, g, name);
  for (size_t i = 0; i < count; ++i) out[i] = m.row(static_cast<Eigen::Index>(i)).transpose();
  return out;
}

// Per-object scale: `scale [O,3]`, or older Physion files' `scale_x/scale_y/scale_z [O]`.
std::vector<Vec3> read_scales(const Group& g, size_t count) {
  if (g.has("scale") || !(g.has("scale_x") && g.has("scale_y") && g.has("scale_z"))) {
    return optional_vec3(g, "scale", count, Vec3::Ones());
  }
  const std::vector<double> x = optional_vector(g, {"scale_x"}, count, 1.0);
  const std::vector<double> y = optional_vector(g, {"scale_y"}, count, 1.0);
  const std::vector<double> z = optional_vector(g, {"scale_z"}, count, 1.0);
  std::vector<Vec3> out(count);
  for (size_t i = 0; i < count; ++i) out[i] = Vec3(x[i], y[i], z[i]);
  return out;
}

std::vector<int32_t> read_object_ids(const Group& g) {
  const std::vector<int64_t> raw = g.read_int_vector("object_ids", -1);
  std::vector<int32_t> ids;
  std::set<int64_t> seen;
  for (size_t i = 0; i < raw.size(); ++i) {
    if (raw[i] < std::numeric_limits<int32_t>::min() ||
        raw[i] > std::numeric_limits<int32_t>::max()) {
      throw FormatError(g.file(), g.child_path("object_ids"),
                        "id " + std::to_string(raw[i]) + " does not fit in int32");
    }
    if (!seen.insert(raw[i]).second) {
      throw FormatError(
          g.file(), g.child_path("object_ids"),
          "duplicate id " + std::to_string(raw[i]) + " at index " + std::to_string(i));
    }
    ids.push_back(static_cast<int32_t>(raw[i]));
  }
  return ids;
}

std::vector<Role> read_roles(const Group& g, const std::vector<int32_t>& ids) {
  std::vector<Role> roles(ids.size(), Role::kOther);
  if (g.has("roles")) {
    const std::vector<std::string> names =
        g.read_strings("roles", static_cast<int64_t>(ids.size()));
    for (size_t i = 0; i < names.size(); ++i) {
      try {
        roles[i] = parse_role(names[i]);
      } catch (const ValueError& e) {
        throw FormatError(g.file(), g.child_path("roles"),
                          "index " + std::to_string(i) + ": " + e.what());
      }
    }
    return roles;
  }
  // Physion names the target and the zone by object id.
  for (const auto& [name, role] :
       {std::pair{"target_id", Role::kTarget}, std::pair{"zone_id", Role::kZone}}) {
    if (!g.has(name)) continue;
    const int64_t id = g.read_int_scalar(name);
    if (id == -1) continue;
    const auto it = std::find(ids.begin(), ids.end(), id);
    if (it == ids.end()) {
      throw FormatError(g.file(), g.child_path(name),
                        "id " + std::to_string(id) + " is not in static/object_ids");
    }
    roles[static_cast<size_t>(it - ids.begin())] = role;
  }
  return roles;
}

Mesh read_mesh(const Group& mesh_group, size_t index, const Mat3& axes) {
  const std::string vname = "vertices_" + std::to_string(index);
  const std::string fname = "faces_" + std::to_string(index);
  const MatrixXdR v = mesh_group.read_matrix(vname, -1, 3);
  require_finite(v, mesh_group, vname);
  const h5::MatrixXlR f = mesh_group.read_int_matrix(fname, -1, 3);
  for (Eigen::Index r = 0; r < f.rows(); ++r) {
    for (int c = 0; c < 3; ++c) {
      if (f(r, c) < 0 || f(r, c) >= v.rows()) {
        throw FormatError(mesh_group.file(), mesh_group.child_path(fname),
                          "index " + std::to_string(f(r, c)) + " in row " + std::to_string(r) +
                              " is out of range for " + std::to_string(v.rows()) + " vertices");
      }
    }
  }
  Mesh mesh;
  mesh.vertices = v * axes.transpose();
  mesh.faces = f.cast<int32_t>();
  // A reflection (det A < 0) turns counter-clockwise triangles clockwise; swap two corners.
  if (axes.determinant() < 0) mesh.faces.col(1).swap(mesh.faces.col(2));
  return mesh;
}

Quat read_rotation(const MatrixXdR& rows, Eigen::Index r, const FileConvention& conv,
                   const Group& g) {
  const Eigen::RowVector4d q = rows.row(r);
  Quat out = conv.quaternion_xyzw ? Quat(q[3], q[0], q[1], q[2]) : Quat(q[0], q[1], q[2], q[3]);
  const double norm = out.norm();
  if (!(norm > kMinQuaternionNorm)) {
    throw FormatError(g.file(), g.child_path("rotations"),
                      "zero quaternion in row " + std::to_string(r));
  }
  if (std::abs(norm - 1.0) > kUnitTolerance) out.normalize();
  if (conv.axes.isIdentity(0.0)) return out;
  const Mat3 rotation = conv.axes * out.toRotationMatrix() * conv.axes.transpose();
  return Quat(rotation).normalized();
}

// `name` with bytes outside printable ASCII written as \xNN, so an error stays one readable line.
std::string printable(const std::string& name) {
  std::string out;
  for (unsigned char c : name) {
    if (c >= 0x20 && c < 0x7f) {
      out += static_cast<char>(c);
    } else {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", c);
      out += buf;
    }
  }
  return out;
}

// Frame groups must be named by consecutive integers from 0 ("0000", "0001", ...).
std::vector<std::string> frame_groups(const Group& frames) {
  std::map<int64_t, std::string> by_index;
  for (const std::string& name : frames.children()) {
    const bool digits =
        !name.empty() && name.size() <= 9 &&
        std::all_of(name.begin(), name.end(), [](unsigned char c) { return std::isdigit(c) != 0; });
    if (!digits) {
      throw FormatError(frames.file(), frames.child_path(printable(name)),
                        "frame groups must be named by their index (0000, 0001, ...)");
    }
    by_index[std::stoll(name)] = name;
  }
  std::vector<std::string> names;
  for (const auto& [index, name] : by_index) {
    if (index != static_cast<int64_t>(names.size())) {
      throw FormatError(
          frames.file(), frames.child_path(frame_name(static_cast<int>(names.size()))),
          "missing frame (frames must be numbered 0.." + std::to_string(by_index.size() - 1) + ")");
    }
    names.push_back(name);
  }
  return names;
}

}  // namespace

Scene read_scene_file(const Group& root, const FileConvention& conv) {
  const std::string& path = root.file();
  Scene scene;
  scene.scenario = root.string_attribute("scenario").value_or(conv.default_scenario);
  scene.seed = root.uint_attribute("seed").value_or(0);
  const std::optional<double> dt = root.double_attribute("dt");
  if (!dt && !conv.default_dt) throw FormatError(path, "@dt", "missing root attribute");
  scene.dt_s = dt.value_or(conv.default_dt.value_or(0.0));
  // An hour between frames is no dynamics scene; a huge dt overflows every velocity.
  if (!(scene.dt_s > 0) || !(scene.dt_s <= 3600)) {
    throw FormatError(path, "@dt",
                      "must be in (0, 3600] seconds, got " + std::to_string(scene.dt_s));
  }

  const Group statics = root.group("static");
  const std::vector<int32_t> ids = read_object_ids(statics);
  const size_t count = ids.size();
  std::vector<std::string> names(count);
  for (size_t i = 0; i < count; ++i) names[i] = "object_" + std::to_string(ids[i]);
  for (const char* key : {"names", "model_names"}) {
    if (statics.has(key)) {
      names = statics.read_strings(key, static_cast<int64_t>(count));
      break;
    }
  }
  std::vector<bool> rigid(count, true);
  if (statics.has("rigid")) {
    const std::vector<int64_t> flags =
        statics.read_int_vector("rigid", static_cast<int64_t>(count));
    for (size_t i = 0; i < count; ++i) rigid[i] = flags[i] != 0;
  }
  const std::vector<Vec3> scales = read_scales(statics, count);
  const std::vector<double> mass = optional_vector(statics, {"mass"}, count, Object{}.mass);
  const std::vector<double> friction =
      optional_vector(statics, {"friction", "static_friction"}, count, Object{}.friction);
  const std::vector<double> restitution =
      optional_vector(statics, {"restitution", "bounciness"}, count, Object{}.restitution);
  require_non_negative(mass, statics, "mass");
  require_non_negative(friction, statics, "friction");
  require_non_negative(restitution, statics, "restitution");
  for (size_t i = 0; i < count; ++i) {
    if (!(scales[i].minCoeff() > 0)) {
      throw FormatError(
          path, statics.child_path("scale"),
          "must be > 0 on every axis, got a non-positive value at index " + std::to_string(i));
    }
  }
  const std::vector<Vec3> colors = optional_vec3(statics, "color", count, Object{}.color);
  const std::vector<Role> roles = read_roles(statics, ids);
  const Mat3 abs_axes = conv.axes.cwiseAbs();

  scene.objects.resize(count);
  if (count > 0) {
    const Group meshes = statics.group("mesh");
    for (size_t i = 0; i < count; ++i) {
      Object& o = scene.objects[i];
      o.id = ids[i];
      o.name = names[i];
      o.role = roles[i];
      o.rigid = rigid[i];
      o.mesh = read_mesh(meshes, i, conv.axes);
      o.scale = abs_axes * scales[i];
      o.mass = mass[i];
      o.friction = friction[i];
      o.restitution = restitution[i];
      o.color = colors[i];
    }
  }

  const Group frames = root.group("frames");
  const std::vector<std::string> frame_names = frame_groups(frames);
  const size_t num_frames = frame_names.size();
  if (const std::optional<int64_t> declared = root.int_attribute("num_frames")) {
    if (*declared != static_cast<int64_t>(num_frames)) {
      throw FormatError(path, "@num_frames",
                        "says " + std::to_string(*declared) + " but the file has " +
                            std::to_string(num_frames) + " frame groups");
    }
  }
  scene.trajectories.resize(count);
  for (size_t i = 0; i < count; ++i) {
    if (rigid[i]) {
      scene.trajectories[i].poses.resize(num_frames);
    } else {
      scene.trajectories[i].particles.resize(num_frames);
    }
  }
  // Label values per name and frame; NaN marks a frame without the label.
  std::map<std::string, std::vector<double>> labels;
  std::map<std::string, size_t> label_seen;
  for (size_t t = 0; t < num_frames; ++t) {
    const Group frame = frames.group(frame_names[t]);
    const Group objects = frame.group("objects");
    const MatrixXdR positions = objects.read_matrix("positions", static_cast<int64_t>(count), 3);
    require_finite(positions, objects, "positions");
    const MatrixXdR rotations = objects.read_matrix("rotations", static_cast<int64_t>(count), 4);
    require_finite(rotations, objects, "rotations");
    for (size_t i = 0; i < count; ++i) {
      const auto row = static_cast<Eigen::Index>(i);
      if (rigid[i]) {
        Pose& pose = scene.trajectories[i].poses[t];
        pose.position = conv.axes * positions.row(row).transpose();
        pose.rotation = read_rotation(rotations, row, conv, objects);
      } else {
        const Group particles = frame.group("particles");
        const std::string name = std::to_string(i);
        const MatrixXdR p = particles.read_matrix(name, scene.objects[i].mesh.num_vertices(), 3);
        require_finite(p, particles, name);
        scene.trajectories[i].particles[t] = p * conv.axes.transpose();
      }
    }
    if (!frame.has("labels")) continue;
    const Group label_group = frame.group("labels");
    for (const std::string& name : label_group.children()) {
      if (conv.skip_irregular_labels) {
        const bool regular = label_group.has_dataset(name) && [&] {
          const h5::Shape s = label_group.shape(name);
          const bool single = s.dims.empty() || (s.dims.size() == 1 && s.dims[0] == 1);
          return single && (s.type_class == H5T_INTEGER || s.type_class == H5T_FLOAT ||
                            s.type_class == H5T_ENUM);
        }();
        if (!regular) continue;
      }
      const double value = label_group.read_scalar(name);
      if (!std::isfinite(value)) {
        // Lenient files: a label without a value in some frame is skipped like a missing one.
        if (conv.skip_irregular_labels) continue;
        throw FormatError(path, label_group.child_path(name), "non-finite label value");
      }
      labels.try_emplace(name, num_frames, std::numeric_limits<double>::quiet_NaN())
          .first->second[t] = value;
      ++label_seen[name];
    }
  }
  for (auto& [name, values] : labels) {
    if (label_seen[name] == num_frames) {
      scene.labels[name] = std::move(values);
      continue;
    }
    const size_t missing = static_cast<size_t>(
        std::find_if(values.begin(), values.end(), [](double v) { return std::isnan(v); }) -
        values.begin());
    if (conv.skip_irregular_labels) {
      log_debug(path, ": label '", name, "' is missing in some frames; skipped");
      continue;
    }
    throw FormatError(path, "frames/" + frame_names[missing] + "/labels/" + name,
                      "missing (the label exists in other frames)");
  }

  try {
    scene.validate();
  } catch (const ValueError& e) {
    throw FormatError(path, "scene", e.what());
  }
  return scene;
}

}  // namespace dynscope
