// HDF5 scene files: the dynscope layout (writer and reader) and format detection.
//
// Scene file layout (format_version 1; README.md "Scene file format" has the same text with an
// h5py example). Modelled on Physion's HDF5 files so that one reader opens both.
//
//   /  (root attributes)
//     format            string   "dynscope-scene"
//     format_version    int      1
//     up_axis           string   "z"      (gravity is -z; coordinates are right-handed)
//     quaternion_order  string   "wxyz"   ("xyzw" is accepted when reading)
//     scenario          string   generator name, e.g. "movi-a", "drop"           (optional)
//     seed              uint64   generator seed                                    (optional)
//     dt                float64  seconds between stored frames
//     num_frames        int      number of frame groups                            (optional)
//   /static
//     object_ids        [O]   int32    unique object ids
//     names             [O]   string   (optional, default "object_<id>")
//     roles             [O]   string   target | zone | probe | other  (optional; without it
//                                      target_id / zone_id decide, every other object is "other")
//     target_id, zone_id      int32    scalar object id, -1 for none
//     rigid             [O]   uint8    1 rigid (posed mesh), 0 deformable (particles) (default 1)
//     scale             [O,3] float64  per-axis scale applied to the mesh  (default 1)
//     mass              [O]   float64  kg, 0 = static                     (default 1)
//     friction          [O]   float64  Coulomb coefficient                (default 0.5)
//     restitution       [O]   float64  in [0,1]                           (default 0.5)
//     color             [O,3] float64  linear RGB in [0,1]                (default 0.6 grey)
//     mesh/vertices_<i> [V,3] float64  object frame, UNSCALED, i = object index 0..O-1
//     mesh/faces_<i>    [F,3] int32    vertex indices, counter-clockwise seen from outside
//   /frames/NNNN        NNNN = frame index, zero-padded to 4 digits, 0..T-1 without gaps
//     objects/positions [O,3] float64  world position of each object's frame origin
//     objects/rotations [O,4] float64  world rotation quaternion, w x y z
//     particles/<i>     [V,3] float64  world vertex positions of deformable object i
//                                      (its positions/rotations rows hold the particle
//                                      centroid and the identity and are not read back)
//     labels/<name>     scalar float64 per-frame label, e.g. target_contacting_zone (0/1);
//                                      a label present in one frame must be in every frame
//
// World vertex j of rigid object i at frame t:
//   rotation_t,i * (scale_i ⊙ vertices_i[j]) + position_t,i
// Strings are written fixed-length UTF-8 (h5py returns bytes). Readers accept any integer or
// float type for numbers (and h5py bools for labels), fixed or variable-length strings, and
// ignore datasets and attributes they do not know. Files without the up_axis and
// quaternion_order attributes are read as Physion files (physion_reader.cpp).
#include "engine/io/scene_file.h"

#include <cstdio>
#include <cstring>
#include <fstream>

#include "engine/core/error.h"
#include "engine/io/h5_util.h"
#include "engine/io/scene_reader.h"
#include "engine/io/temp_file.h"

namespace dynscope {
namespace {

constexpr const char* kFormatName = "dynscope-scene";
constexpr int64_t kFormatVersion = 1;

std::string frame_name(int frame) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "%04d", frame);
  return buf;
}

int32_t id_with_role(const Scene& scene, Role role) {
  const int index = scene.find_role(role);
  return index < 0 ? -1 : scene.objects[static_cast<size_t>(index)].id;
}

void write_static(const h5::Group& root, const Scene& scene) {
  const size_t count = scene.objects.size();
  std::vector<int32_t> ids;
  std::vector<std::string> names, roles;
  std::vector<uint8_t> rigid;
  std::vector<double> mass, friction, restitution;
  Points scale(static_cast<Eigen::Index>(count), 3), color(static_cast<Eigen::Index>(count), 3);
  for (size_t i = 0; i < count; ++i) {
    const Object& o = scene.objects[i];
    ids.push_back(o.id);
    names.push_back(o.name);
    roles.push_back(role_name(o.role));
    rigid.push_back(o.rigid ? 1 : 0);
    mass.push_back(o.mass);
    friction.push_back(o.friction);
    restitution.push_back(o.restitution);
    scale.row(static_cast<Eigen::Index>(i)) = o.scale.transpose();
    color.row(static_cast<Eigen::Index>(i)) = o.color.transpose();
  }
  const h5::Group statics = root.create_group("static");
  statics.write_int_vector("object_ids", ids);
  statics.write_strings("names", names);
  statics.write_strings("roles", roles);
  statics.write_int_scalar("target_id", id_with_role(scene, Role::kTarget));
  statics.write_int_scalar("zone_id", id_with_role(scene, Role::kZone));
  statics.write_uint8_vector("rigid", rigid);
  statics.write_matrix("scale", scale.data(), count, 3);
  statics.write_vector("mass", mass);
  statics.write_vector("friction", friction);
  statics.write_vector("restitution", restitution);
  statics.write_matrix("color", color.data(), count, 3);
  const h5::Group meshes = statics.create_group("mesh");
  for (size_t i = 0; i < count; ++i) {
    const Mesh& m = scene.objects[i].mesh;
    meshes.write_matrix("vertices_" + std::to_string(i), m.vertices.data(),
                        static_cast<hsize_t>(m.vertices.rows()), 3);
    meshes.write_int_matrix("faces_" + std::to_string(i), m.faces.data(),
                            static_cast<hsize_t>(m.faces.rows()), 3);
  }
}

void write_frames(const h5::Group& root, const Scene& scene) {
  const h5::Group frames = root.create_group("frames");
  const auto count = static_cast<Eigen::Index>(scene.objects.size());
  for (int t = 0; t < scene.num_frames(); ++t) {
    const h5::Group frame = frames.create_group(frame_name(t));
    Points positions(count, 3);
    Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor> rotations(count, 4);
    bool any_deformable = false;
    for (Eigen::Index i = 0; i < count; ++i) {
      const Trajectory& traj = scene.trajectories[static_cast<size_t>(i)];
      if (scene.objects[static_cast<size_t>(i)].rigid) {
        const Pose& pose = traj.poses[static_cast<size_t>(t)];
        positions.row(i) = pose.position.transpose();
        rotations.row(i) << pose.rotation.w(), pose.rotation.x(), pose.rotation.y(),
            pose.rotation.z();
      } else {
        // Informational for h5py users; the particles are the state of a deformable object.
        const Points& p = traj.particles[static_cast<size_t>(t)];
        const Vec3 centroid = p.rows() > 0 ? Vec3(p.colwise().mean().transpose()) : Vec3::Zero();
        positions.row(i) = centroid.transpose();
        rotations.row(i) << 1.0, 0.0, 0.0, 0.0;
        any_deformable = true;
      }
    }
    const h5::Group objects = frame.create_group("objects");
    objects.write_matrix("positions", positions.data(), static_cast<hsize_t>(count), 3);
    objects.write_matrix("rotations", rotations.data(), static_cast<hsize_t>(count), 4);
    if (any_deformable) {
      const h5::Group particles = frame.create_group("particles");
      for (Eigen::Index i = 0; i < count; ++i) {
        if (scene.objects[static_cast<size_t>(i)].rigid) continue;
        const Points& p =
            scene.trajectories[static_cast<size_t>(i)].particles[static_cast<size_t>(t)];
        particles.write_matrix(std::to_string(i), p.data(), static_cast<hsize_t>(p.rows()), 3);
      }
    }
    if (!scene.labels.empty()) {
      const h5::Group labels = frame.create_group("labels");
      for (const auto& [name, values] : scene.labels) {
        labels.write_scalar(name, values[static_cast<size_t>(t)]);
      }
    }
  }
}

}  // namespace

bool is_hdf5_file(const std::string& path) {
  static const char kSignature[8] = {'\x89', 'H', 'D', 'F', '\r', '\n', '\x1a', '\n'};
  std::ifstream in(path, std::ios::binary);
  char head[8] = {};
  if (!in.read(head, sizeof head)) return false;
  return std::memcmp(head, kSignature, sizeof head) == 0;
}

void write_scene(const Scene& scene, const std::string& path) {
  scene.validate();
  for (const auto& [name, values] : scene.labels) {
    if (name.empty() || name == "." || name.find('/') != std::string::npos) {
      throw ValueError("label '" + name + "'", "label names must be non-empty and contain no '/'");
    }
  }
  TempFile temp(path);
  {
    h5::Group root = h5::Group::create_file(temp.path());
    root.write_attribute("format", std::string(kFormatName));
    root.write_attribute("format_version", kFormatVersion);
    root.write_attribute("up_axis", std::string("z"));
    root.write_attribute("quaternion_order", std::string("wxyz"));
    root.write_attribute("scenario", scene.scenario);
    root.write_attribute("seed", scene.seed);
    root.write_attribute("dt", scene.dt_s);
    root.write_attribute("num_frames", static_cast<int64_t>(scene.num_frames()));
    write_static(root, scene);
    write_frames(root, scene);
    root.close();
  }
  temp.commit();
}

Scene read_scene(const std::string& path) {
  const h5::Group root = h5::Group::open_file(path);
  const std::optional<std::string> up = root.string_attribute("up_axis");
  const std::optional<std::string> order = root.string_attribute("quaternion_order");
  if (!up && !order) return read_scene_file(root, physion_convention());
  if (!up) throw FormatError(path, "@up_axis", "missing (quaternion_order is present)");
  if (!order) throw FormatError(path, "@quaternion_order", "missing (up_axis is present)");
  if (*up != "z") {
    throw FormatError(path, "@up_axis",
                      "unsupported value '" + *up + "' (dynscope files are z-up)");
  }
  if (*order != "wxyz" && *order != "xyzw") {
    throw FormatError(path, "@quaternion_order",
                      "unsupported value '" + *order + "' (wxyz or xyzw)");
  }
  if (const auto format = root.string_attribute("format"); format && *format != kFormatName) {
    throw FormatError(path, "@format", "is '" + *format + "', expected '" + kFormatName + "'");
  }
  if (const auto version = root.int_attribute("format_version");
      version && (*version < 1 || *version > kFormatVersion)) {
    throw FormatError(path, "@format_version",
                      "version " + std::to_string(*version) +
                          " is not supported (this build reads " + std::to_string(kFormatVersion) +
                          ")");
  }
  FileConvention convention;
  convention.quaternion_xyzw = *order == "xyzw";
  return read_scene_file(root, convention);
}

}  // namespace dynscope
