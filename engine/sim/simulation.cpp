// Rolls a SimSetup out in a BulletWorld and records poses and the target-zone contact label.
#include "engine/sim/simulation.h"

#include <cmath>
#include <set>

#include "engine/core/error.h"
#include "engine/sim/bullet_world.h"

namespace dynscope {
namespace {

void check_setup(const SimSetup& s) {
  if (!(s.physics_rate_hz > 0) || !std::isfinite(s.physics_rate_hz)) {
    throw ValueError("physics_rate_hz",
                     "must be positive, got " + std::to_string(s.physics_rate_hz));
  }
  if (s.substeps_per_frame < 1) {
    throw ValueError("substeps_per_frame",
                     "must be >= 1, got " + std::to_string(s.substeps_per_frame));
  }
  if (s.num_frames < 1)
    throw ValueError("num_frames", "must be >= 1, got " + std::to_string(s.num_frames));
  if (!(s.contact_tolerance >= 0)) throw ValueError("contact_tolerance", "must be >= 0");
  if (s.bodies.empty()) throw ValueError("bodies", "a setup needs at least one body");
  std::set<int32_t> ids;
  for (const BodySpec& b : s.bodies) {
    if (!ids.insert(b.object.id).second) {
      throw ValueError("body " + std::to_string(b.object.id), "duplicate object id");
    }
  }
}

}  // namespace

Scene simulate(const SimSetup& setup) {
  check_setup(setup);
  WorldOptions options;
  options.gravity = setup.gravity;
  options.physics_dt_s = 1.0 / setup.physics_rate_hz;
  options.floor = setup.floor;
  options.floor_friction = setup.floor_friction;
  options.floor_restitution = setup.floor_restitution;
  BulletWorld world(options);

  Scene scene;
  scene.scenario = setup.scenario;
  scene.seed = setup.seed;
  scene.dt_s = setup.frame_dt_s();
  for (const BodySpec& body : setup.bodies) {
    world.add_body(body);
    Object o = body.object;
    o.rigid = true;
    o.mesh = body_mesh(body.parts);
    scene.objects.push_back(std::move(o));
  }
  for (const BallJoint& j : setup.joints) world.add_ball_joint(j.body_a, j.body_b, j.pivot);

  const int target = scene.find_role(Role::kTarget);
  const int zone = scene.find_role(Role::kZone);
  const bool labelled = target >= 0 && zone >= 0;
  std::vector<double> label;
  const auto n = static_cast<size_t>(world.num_bodies());
  scene.trajectories.resize(n);
  auto record = [&] {
    for (size_t i = 0; i < n; ++i)
      scene.trajectories[i].poses.push_back(world.pose(static_cast<int>(i)));
  };

  world.detect_contacts();
  record();
  if (labelled)
    label.push_back(world.in_contact(target, zone, setup.contact_tolerance) ? 1.0 : 0.0);
  for (int f = 1; f < setup.num_frames; ++f) {
    bool touched = false;
    for (int s = 0; s < setup.substeps_per_frame; ++s) {
      world.step();
      // A short bounce can begin and end between two stored frames; it still counts.
      if (labelled) touched = touched || world.in_contact(target, zone, setup.contact_tolerance);
    }
    record();
    if (labelled) label.push_back(touched ? 1.0 : 0.0);
  }
  if (labelled) scene.labels[kContactLabel] = std::move(label);
  return scene;
}

bool contact_outcome(const Scene& scene) {
  const auto it = scene.labels.find(kContactLabel);
  if (it == scene.labels.end()) return false;
  for (double v : it->second) {
    if (v > 0.5) return true;
  }
  return false;
}

}  // namespace dynscope
