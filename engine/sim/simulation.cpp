// Rolls a SimSetup out in a BulletWorld and records poses and the target-zone contact label.
#include "engine/sim/simulation.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
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

void set_frame_rate(SimSetup& setup, double frame_rate_hz) {
  check_setup(setup);
  const int64_t steps = static_cast<int64_t>(setup.num_frames - 1) * setup.substeps_per_frame;
  // A frame must fall on a physics step: the rates that fit are physics_rate / s for whole s (the
  // whole rates among them are listed). An interval that does not divide the run's steps runs the
  // simulation on to the next whole frame.
  std::string fitting;
  int substeps = 0;
  for (int64_t s = 1; s <= std::max<int64_t>(steps, 1); ++s) {
    const double rate = setup.physics_rate_hz / static_cast<double>(s);
    if (std::abs(rate - frame_rate_hz) <= 1e-9 * rate) substeps = static_cast<int>(s);
    if (rate == std::floor(rate)) {  // 240, 120, 80, 60, 48, ..., 1 for 240 Hz physics
      char text[32];
      std::snprintf(text, sizeof text, "%s%g", fitting.empty() ? "" : ", ", rate);
      fitting += text;
    }
  }
  if (substeps == 0) {
    char text[96];
    std::snprintf(text, sizeof text, "%g Hz is not a whole number of %g Hz physics steps",
                  frame_rate_hz, setup.physics_rate_hz);
    throw ValueError("frame_rate", std::string(text) + " (rates that fit: " + fitting + ")");
  }
  setup.substeps_per_frame = substeps;
  setup.num_frames = static_cast<int>((steps + substeps - 1) / substeps) + 1;
}

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
    o.mesh = body_mesh(body.parts, setup.mesh_density);
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

int first_labelled_contact(const Scene& scene) {
  const auto it = scene.labels.find(kContactLabel);
  if (it == scene.labels.end()) return -1;
  for (size_t f = 0; f < it->second.size(); ++f) {
    if (it->second[f] > 0.5) return static_cast<int>(f);
  }
  return -1;
}

bool contact_outcome(const Scene& scene) { return first_labelled_contact(scene) >= 0; }

}  // namespace dynscope
