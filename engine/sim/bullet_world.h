// Small RAII wrapper of a Bullet dynamics world built from our body descriptions (no Bullet types).
#pragma once

#include <memory>

#include "engine/core/types.h"
#include "engine/sim/simulation.h"

namespace dynscope {

/// World-wide settings of a BulletWorld.
struct WorldOptions {
  double gravity = 9.81;              ///< m/s² along -z.
  double physics_dt_s = 1.0 / 240.0;  ///< Fixed step length.
  bool floor = true;                  ///< Static plane z = 0.
  double floor_friction = 0.5;
  double floor_restitution = 0.2;
};

/// One Bullet discrete dynamics world. Bodies are numbered in the order they are added; the floor
/// is not a body. Not thread-safe; separate worlds may run on separate threads.
class BulletWorld {
 public:
  /// Throws ValueError for a non-positive step or non-finite gravity.
  explicit BulletWorld(const WorldOptions& options);
  ~BulletWorld();
  BulletWorld(const BulletWorld&) = delete;
  BulletWorld& operator=(const BulletWorld&) = delete;

  /// Adds a rigid body (static if `body.object.mass` is 0) and returns its index. Throws
  /// ValueError (naming the object) for invalid parts, scale or material values.
  int add_body(const BodySpec& body);
  /// Ties bodies `a` and `b` at the world point `pivot` (their current poses) with a ball joint;
  /// the two bodies stop colliding with each other. Throws ValueError for bad indices.
  void add_ball_joint(int a, int b, const Vec3& pivot);

  /// True if `body` placed as described would touch or penetrate (contact distance <= `tolerance`)
  /// any body of the world or the floor. The world is not changed.
  bool overlaps(const BodySpec& body, double tolerance) const;

  /// Runs collision detection only (no motion), so contact queries see the current poses.
  void detect_contacts();
  /// Advances the world by one fixed step.
  void step();

  int num_bodies() const;
  /// World pose of body `i` (its centre-of-mass frame).
  Pose pose(int i) const;
  /// World linear velocity of body `i`, m/s.
  Vec3 linear_velocity(int i) const;
  /// Distance between the collision shapes of bodies `a` and `b` at their current poses (scene
  /// units, negative when they overlap), from Bullet's GJK/EPA.
  double distance(int a, int b) const;
  /// True if the last collision pass found a contact point between bodies `a` and `b` whose
  /// distance is <= `tolerance` (negative distance = penetration), or, when their bounds are
  /// that close, distance(a, b) <= `tolerance` (Bullet's box-box manifolds stay empty for boxes
  /// that touch without penetrating).
  bool in_contact(int a, int b, double tolerance) const;
  /// Deepest penetration depth (>= 0, scene units) over all contact points of the last collision
  /// pass between bodies, or between bodies and the floor.
  double max_penetration() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace dynscope
