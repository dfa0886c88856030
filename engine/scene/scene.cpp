// Scene data model helpers and consistency checks.
#include "engine/scene/scene.h"

#include "engine/core/error.h"

namespace dynscope {

const char* role_name(Role role) {
  switch (role) {
    case Role::kTarget:
      return "target";
    case Role::kZone:
      return "zone";
    case Role::kProbe:
      return "probe";
    case Role::kOther:
      break;
  }
  return "other";
}

Role parse_role(const std::string& name) {
  if (name == "target") return Role::kTarget;
  if (name == "zone") return Role::kZone;
  if (name == "probe") return Role::kProbe;
  if (name == "other") return Role::kOther;
  throw ValueError("role", "unknown role '" + name + "' (target, zone, probe, other)");
}

int Scene::num_frames() const {
  if (objects.empty() || trajectories.empty()) return 0;
  const Trajectory& t = trajectories.front();
  return static_cast<int>(objects.front().rigid ? t.poses.size() : t.particles.size());
}

int Scene::object_index(int32_t id) const {
  for (size_t i = 0; i < objects.size(); ++i) {
    if (objects[i].id == id) return static_cast<int>(i);
  }
  return -1;
}

int Scene::find_role(Role role) const {
  for (size_t i = 0; i < objects.size(); ++i) {
    if (objects[i].role == role) return static_cast<int>(i);
  }
  return -1;
}

Points Scene::world_vertices(int i, int frame) const {
  const Object& o = objects.at(static_cast<size_t>(i));
  const Trajectory& t = trajectories.at(static_cast<size_t>(i));
  if (!o.rigid) return t.particles.at(static_cast<size_t>(frame));
  return t.poses.at(static_cast<size_t>(frame)).apply(o.scaled_mesh().vertices);
}

Aabb Scene::bounds() const {
  Aabb box;
  for (size_t i = 0; i < objects.size(); ++i) {
    for (int f = 0; f < num_frames(); ++f) box.extend(Aabb::of(world_vertices(static_cast<int>(i), f)));
  }
  return box;
}

void Scene::validate() const {
  if (trajectories.size() != objects.size()) {
    throw ValueError("trajectories", std::to_string(trajectories.size()) + " trajectories for " +
                                         std::to_string(objects.size()) + " objects");
  }
  if (!(dt_s > 0)) throw ValueError("dt", "must be positive, got " + std::to_string(dt_s));
  const auto frames = static_cast<size_t>(num_frames());
  for (size_t i = 0; i < objects.size(); ++i) {
    const Object& o = objects[i];
    const std::string what = "object " + std::to_string(o.id) + " (" + o.name + ")";
    o.mesh.validate(what);
    if (!o.scale.allFinite()) throw ValueError(what, "scale is not finite");
    if (object_index(o.id) != static_cast<int>(i)) throw ValueError(what, "duplicate object id");
    const Trajectory& t = trajectories[i];
    const size_t n = o.rigid ? t.poses.size() : t.particles.size();
    if (n != frames) {
      throw ValueError(what, "has " + std::to_string(n) + " frames, expected " +
                                 std::to_string(frames));
    }
    for (size_t f = 0; f < t.poses.size(); ++f) {
      if (!t.poses[f].position.allFinite() || !t.poses[f].rotation.coeffs().allFinite()) {
        throw ValueError(what, "non-finite pose at frame " + std::to_string(f));
      }
    }
    for (size_t f = 0; f < t.particles.size(); ++f) {
      if (t.particles[f].rows() != o.mesh.vertices.rows() || !t.particles[f].allFinite()) {
        throw ValueError(what, "bad particle positions at frame " + std::to_string(f));
      }
    }
  }
  for (const auto& [name, values] : labels) {
    if (values.size() != frames) {
      throw ValueError("label " + name, "has " + std::to_string(values.size()) +
                                            " frames, expected " + std::to_string(frames));
    }
  }
}

}  // namespace dynscope
