// Ground-truth scene: objects, their per-frame states and per-frame labels (DESIGN §3).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "engine/core/types.h"
#include "engine/scene/mesh.h"

namespace dynscope {

/// What an object is for in a contact scenario.
enum class Role { kTarget, kZone, kProbe, kOther };

/// "target", "zone", "probe" or "other".
const char* role_name(Role role);
/// Inverse of role_name; throws ValueError for an unknown name.
Role parse_role(const std::string& name);

/// One object: identity, physical material and its mesh in the object frame (unscaled).
struct Object {
  int32_t id = 0;
  std::string name;
  Role role = Role::kOther;
  bool rigid = true;
  /// Mesh in the object's local frame; world vertices are pose.apply(mesh.scaled(scale)).
  Mesh mesh;
  Vec3 scale = Vec3::Ones();
  double mass = 1.0;                 ///< kg; 0 means static (immovable).
  double friction = 0.5;             ///< Coulomb coefficient.
  double restitution = 0.5;          ///< Bounciness in [0, 1].
  Vec3 color = Vec3(0.6, 0.6, 0.6);  ///< Linear RGB in [0, 1].

  /// The mesh with `scale` applied (still in the object frame).
  Mesh scaled_mesh() const { return mesh.scaled(scale); }
  /// A static body (mass 0): the simulation never moves it (tables, ramps, containers, zones).
  bool is_static() const { return mass == 0.0; }
};

/// Per-frame state of one object: poses for rigid objects, vertex positions for deformable ones.
struct Trajectory {
  std::vector<Pose> poses;        ///< `[T]` world poses (rigid objects).
  std::vector<Points> particles;  ///< `[T]` of `[V,3]` world positions (deformable objects).
};

/// A recorded scene: objects, their trajectories over `num_frames()` frames, and labels.
struct Scene {
  std::string scenario;  ///< Generator name ("movi-a", "drop", ...) or "physion".
  uint64_t seed = 0;
  double dt_s = 1.0 / 12.0;  ///< Seconds between stored frames.
  std::vector<Object> objects;
  std::vector<Trajectory> trajectories;  ///< One per object, same order as `objects`.
  /// Per-frame scalar labels (e.g. "target_contacting_zone"), each `[T]`.
  std::map<std::string, std::vector<double>> labels;

  /// Number of stored frames (0 for no objects).
  int num_frames() const;
  /// Index of the object with `id` or -1.
  int object_index(int32_t id) const;
  /// Index of the first object with `role` or -1.
  int find_role(Role role) const;
  /// World-space vertices of object `i` at `frame` (posed scaled mesh, or its particles).
  Points world_vertices(int i, int frame) const;
  /// Bounding box over all objects and frames.
  Aabb bounds() const;
  /// Throws ValueError naming the first inconsistency (frame counts, mesh indices, NaN, ...).
  void validate() const;
};

}  // namespace dynscope
