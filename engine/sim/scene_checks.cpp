// Interpenetration measurement of stored scenes (convex hull per mesh component, Bullet contacts).
#include "engine/sim/scene_checks.h"

#include <numeric>

#include "engine/core/error.h"
#include "engine/sim/bullet_world.h"

namespace dynscope {
namespace {

// Splits a mesh into its connected components (vertices linked by faces).
std::vector<Mesh> components(const Mesh& mesh) {
  const auto n = static_cast<int>(mesh.num_vertices());
  std::vector<int> parent(static_cast<size_t>(n));
  std::iota(parent.begin(), parent.end(), 0);
  auto root = [&](int v) {
    while (parent[static_cast<size_t>(v)] != v) {
      parent[static_cast<size_t>(v)] = parent[static_cast<size_t>(parent[static_cast<size_t>(v)])];
      v = parent[static_cast<size_t>(v)];
    }
    return v;
  };
  for (Eigen::Index f = 0; f < mesh.num_faces(); ++f) {
    for (int e = 1; e < 3; ++e)
      parent[static_cast<size_t>(root(mesh.faces(f, e)))] = root(mesh.faces(f, 0));
  }
  std::vector<int> component_of(static_cast<size_t>(n), -1), local(static_cast<size_t>(n), -1);
  std::vector<Mesh> out;
  std::vector<std::vector<int>> members;
  for (int v = 0; v < n; ++v) {
    const int r = root(v);
    if (component_of[static_cast<size_t>(r)] < 0) {
      component_of[static_cast<size_t>(r)] = static_cast<int>(members.size());
      members.emplace_back();
    }
    const int c = component_of[static_cast<size_t>(r)];
    local[static_cast<size_t>(v)] = static_cast<int>(members[static_cast<size_t>(c)].size());
    members[static_cast<size_t>(c)].push_back(v);
  }
  out.resize(members.size());
  for (size_t c = 0; c < members.size(); ++c) {
    out[c].vertices.resize(static_cast<Eigen::Index>(members[c].size()), 3);
    for (size_t i = 0; i < members[c].size(); ++i) {
      out[c].vertices.row(static_cast<Eigen::Index>(i)) = mesh.vertices.row(members[c][i]);
    }
  }
  std::vector<std::vector<Eigen::Vector3i>> faces(members.size());
  for (Eigen::Index f = 0; f < mesh.num_faces(); ++f) {
    const int c = component_of[static_cast<size_t>(root(mesh.faces(f, 0)))];
    faces[static_cast<size_t>(c)].emplace_back(local[static_cast<size_t>(mesh.faces(f, 0))],
                                               local[static_cast<size_t>(mesh.faces(f, 1))],
                                               local[static_cast<size_t>(mesh.faces(f, 2))]);
  }
  for (size_t c = 0; c < members.size(); ++c) {
    out[c].faces.resize(static_cast<Eigen::Index>(faces[c].size()), 3);
    for (size_t i = 0; i < faces[c].size(); ++i)
      out[c].faces.row(static_cast<Eigen::Index>(i)) = faces[c][i];
  }
  return out;
}

}  // namespace

double max_penetration(const Scene& scene, int frame, bool floor) {
  if (frame < 0 || frame >= scene.num_frames()) {
    throw ValueError("frame", std::to_string(frame) + " is outside [0, " +
                                  std::to_string(scene.num_frames()) + ")");
  }
  WorldOptions options;
  options.floor = floor;
  BulletWorld world(options);
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const Object& o = scene.objects[i];
    if (!o.rigid) continue;
    BodySpec body;
    body.object.id = o.id;
    body.object.name = o.name;
    // Every body is dynamic so that pairs of static objects are tested as well; nothing moves.
    body.object.mass = 1.0;
    body.collision_margin = 0.0;
    body.pose = scene.trajectories[i].poses.at(static_cast<size_t>(frame));
    for (Mesh& part : components(o.scaled_mesh())) {
      if (part.num_vertices() < 4 || part.num_faces() < 4) continue;
      ShapePart p;
      p.kind = ShapeKind::kConvexHull;
      p.hull_mesh = std::move(part);
      body.parts.push_back(std::move(p));
    }
    if (!body.parts.empty()) world.add_body(body);
  }
  world.detect_contacts();
  return world.max_penetration();
}

}  // namespace dynscope
