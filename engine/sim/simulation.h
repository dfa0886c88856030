// A scenario-independent simulation setup (bodies, joints, rates) and its Bullet rollout to a
// Scene.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "engine/scene/scene.h"
#include "engine/sim/shapes.h"

namespace dynscope {

/// Name of the per-frame label that says whether the target touches the zone (1.0 / 0.0).
inline constexpr const char* kContactLabel = "target_contacting_zone";

/// One rigid body to simulate. `object` carries identity and material (id, name, role, scale,
/// mass in kg with 0 = static, friction, restitution, colour); simulate() fills `object.mesh`
/// from `parts` so the stored mesh always matches the collision shape.
struct BodySpec {
  Object object;
  std::vector<ShapePart> parts;
  Pose pose;  ///< Initial world pose (body frame origin = centre of mass).
  Vec3 linear_velocity = Vec3::Zero();   ///< Initial world velocity, m/s.
  Vec3 angular_velocity = Vec3::Zero();  ///< Initial world angular velocity, rad/s.
  double rolling_friction = 0.0;         ///< Bullet rolling friction (metres; stops rolling balls).
  double collision_margin = -1.0;        ///< Bullet margin in scene units; < 0 picks one by size.
};

/// A ball (point-to-point) joint tying two bodies together at a world point given at frame 0.
struct BallJoint {
  int body_a = 0;  ///< Index into SimSetup::bodies.
  int body_b = 0;  ///< Index into SimSetup::bodies.
  Vec3 pivot = Vec3::Zero();
};

/// Everything needed to roll out one scene: rates, floor, bodies and joints.
struct SimSetup {
  std::string scenario;
  uint64_t seed = 0;
  double gravity = 9.81;           ///< m/s² along -z.
  double physics_rate_hz = 240.0;  ///< Bullet fixed step rate.
  int substeps_per_frame = 8;      ///< Physics steps between stored frames.
  int num_frames = 60;             ///< Stored frames; frame 0 is the initial state.
  bool floor = true;               ///< Implicit static plane z = 0 (not stored as an object).
  double floor_friction = 0.5;
  double floor_restitution = 0.2;
  /// Largest contact-point distance (scene units) that still counts as the target touching the
  /// zone.
  double contact_tolerance = 1e-3;
  /// Tessellation of the stored meshes of primitive parts (not of what Bullet simulates).
  MeshDensity mesh_density = MeshDensity::kDense;
  std::vector<BodySpec> bodies;
  std::vector<BallJoint> joints;

  /// Seconds between stored frames.
  double frame_dt_s() const { return substeps_per_frame / physics_rate_hz; }
};

/// Stores `setup`'s frames at `frame_rate_hz` instead, with the same physics steps:
/// substeps_per_frame becomes physics_rate_hz / frame_rate_hz and num_frames grows or shrinks so
/// that the last frame stays at the same time when the new interval divides the setup's physics
/// steps (a scene at twice the rate is the same scene with one more frame between every two), and
/// comes at the first frame after it otherwise (the simulation runs on by less than one interval;
/// a scene at a third of the rate holds every third frame of its twin). The rate must be a whole
/// number of physics steps. Throws ValueError("frame_rate") naming rates that fit.
void set_frame_rate(SimSetup& setup, double frame_rate_hz);

/// Rolls out `setup` with Bullet and records every body's pose at each stored frame. When one
/// body has role target and one role zone, adds the label kContactLabel: frame 0 is 1 if they
/// touch initially, frame f > 0 is 1 if they touched after any physics step in (f-1, f].
/// Deterministic. Throws ValueError naming the body or field that is inconsistent.
Scene simulate(const SimSetup& setup);

/// The first frame in which `scene`'s kContactLabel is 1; -1 when it never is or is missing.
int first_labelled_contact(const Scene& scene);

/// True if `scene` has kContactLabel and it is 1 in some frame (the Physion scene outcome):
/// first_labelled_contact(scene) >= 0.
bool contact_outcome(const Scene& scene);

}  // namespace dynscope
