// Physion-like contact scenarios (drop, collide, roll, dominoes, support, contain, link).
//
// Every scene has one red target (role target) and one yellow zone (role zone, a static pad
// 2 cm thick lying on the floor) and the per-frame label target_contacting_zone from Bullet's
// contact manifolds (see simulate()). Units are metres, kilograms and seconds at Physion's
// scale (objects 0.05-0.5 m). Common settings: gravity 9.81 m/s² along -z, Bullet at 240 Hz,
// frames stored at 30 fps (8 physics steps per frame), implicit floor z = 0 with friction 0.8
// and restitution 0.5, contact tolerance 1 mm. Materials (uniform): wood (density 600,
// friction 0.6, restitution 0.3), plastic (1000, 0.4, 0.5), metal (2700, 0.3, 0.2), rubber (1100,
// 0.9, 0.7); Bullet multiplies the coefficients of the two bodies in contact; balls and cylinders
// get rolling friction 0.04 x radius. "Random primitive"
// means a box, sphere or cylinder (uniform) with half sizes drawn from the given range.
// Each scenario's sampling ranges are listed by its namespace below and in SCENARIOS.md; the
// ranges straddle the threshold between the two outcomes, so both occur (about half each).
#include <array>
#include <cmath>
#include <nlohmann/json.hpp>

#include "engine/core/error.h"
#include "engine/sim/generators.h"

namespace dynscope::sim {
namespace {

constexpr double kGravity = 9.81;
constexpr double kPhysicsHz = 240.0;
constexpr int kSubsteps = 8;
constexpr double kFloorFriction = 0.8;
constexpr double kFloorRestitution = 0.5;
constexpr double kContactTolerance = 1e-3;
constexpr double kPadHalfThickness = 0.01;
constexpr double kZoneFriction = 0.6;
constexpr double kZoneRestitution = 0.3;
constexpr double kStaticFriction = 0.8;  // tables, ramps, containers
constexpr double kStaticRestitution = 0.3;
// Bullet rolling friction is a length (torque per normal force); radius times a rolling
// resistance coefficient makes balls and cylinders slow down and stop as real ones do.
constexpr double kRollingResistance = 0.04;
const Vec3 kTargetColour(0.85, 0.04, 0.04);
const Vec3 kZoneColour(0.95, 0.8, 0.05);
const Vec3 kProbeColour(0.05, 0.3, 0.85);
const Vec3 kStaticColour(0.55, 0.5, 0.45);
const std::array<Vec3, 6> kOtherColours = {Vec3(0.1, 0.55, 0.2),   Vec3(0.45, 0.15, 0.6),
                                           Vec3(0.1, 0.55, 0.65),  Vec3(0.4, 0.22, 0.08),
                                           Vec3(0.75, 0.75, 0.75), Vec3(0.25, 0.25, 0.3)};

struct Range {
  double lo, hi;
};

double sample(Rng& rng, Range r) { return rng.uniform(r.lo, r.hi); }

nlohmann::json to_json(Range r) { return nlohmann::json::array({r.lo, r.hi}); }

struct Material {
  const char* name;
  double density, friction, restitution;
};
constexpr Material kMaterials[] = {{"wood", 600, 0.6, 0.3},
                                   {"plastic", 1000, 0.4, 0.5},
                                   {"metal", 2700, 0.3, 0.2},
                                   {"rubber", 1100, 0.9, 0.7}};

const char* kind_name(ShapeKind kind) {
  switch (kind) {
    case ShapeKind::kBox:
      return "box";
    case ShapeKind::kSphere:
      return "sphere";
    case ShapeKind::kCylinder:
      return "cylinder";
    case ShapeKind::kConvexHull:
      break;
  }
  return "hull";
}

// Builds one scene: common settings, id bookkeeping and the body helpers every scenario uses.
struct Builder {
  Builder(const char* scenario, uint64_t seed, int frames) : rng(seed) {
    setup.scenario = scenario;
    setup.seed = seed;
    setup.gravity = kGravity;
    setup.physics_rate_hz = kPhysicsHz;
    setup.substeps_per_frame = kSubsteps;
    setup.num_frames = frames;
    setup.floor_friction = kFloorFriction;
    setup.floor_restitution = kFloorRestitution;
    setup.contact_tolerance = kContactTolerance;
  }

  Rng rng;
  SimSetup setup;

  int32_t next_id() const { return static_cast<int32_t>(setup.bodies.size()); }

  // Adds `body` and returns its index (the index is also its id).
  int add(BodySpec body) {
    setup.bodies.push_back(std::move(body));
    return static_cast<int>(setup.bodies.size()) - 1;
  }

  BodySpec& body(int index) { return setup.bodies.at(static_cast<size_t>(index)); }

  const Material& pick_material() { return kMaterials[rng.uniform_int(0, 3)]; }

  void set_material(BodySpec& b) { set_material(b, pick_material()); }

  static void set_material(BodySpec& b, const Material& m) {
    b.object.friction = m.friction;
    b.object.restitution = m.restitution;
    set_density(b, m.density);
  }

  Vec3 role_colour(Role role) {
    switch (role) {
      case Role::kTarget:
        return kTargetColour;
      case Role::kZone:
        return kZoneColour;
      case Role::kProbe:
        return kProbeColour;
      case Role::kOther:
        break;
    }
    return kOtherColours[static_cast<size_t>(rng.uniform_int(0, kOtherColours.size() - 1))];
  }

  // A dynamic box, sphere or cylinder (uniform) with half sizes in `half`, at the origin with
  // identity rotation; spheres and cylinders roll, so rolling friction lets them come to rest.
  BodySpec random_primitive(Role role, Range half) {
    const auto kind = static_cast<ShapeKind>(rng.uniform_int(0, 2));
    return primitive(role, kind, half);
  }

  BodySpec primitive(Role role, ShapeKind kind, Range half) {
    Vec3 scale;
    if (kind == ShapeKind::kBox) {
      scale = Vec3(sample(rng, half), sample(rng, half), sample(rng, half));
    } else if (kind == ShapeKind::kSphere) {
      scale = Vec3::Constant(sample(rng, half));
    } else {
      const double r = sample(rng, half);
      scale = Vec3(r, r, sample(rng, half));
    }
    return primitive_with_scale(role, kind, scale);
  }

  BodySpec primitive_with_scale(Role role, ShapeKind kind, const Vec3& scale) {
    const int32_t id = next_id();
    BodySpec b = primitive_body(id, std::string(kind_name(kind)) + "_" + std::to_string(id), role,
                                kind, scale);
    b.object.color = role_colour(role);
    set_material(b);
    if (kind != ShapeKind::kBox) b.rolling_friction = kRollingResistance * scale.x();
    return b;
  }

  // The yellow zone: a static pad of half size (hx, hy) lying on the floor at (x, y), turned by
  // yaw.
  int add_zone(double hx, double hy, double x, double y, double yaw) {
    const int32_t id = next_id();
    BodySpec b = primitive_body(id, "zone_" + std::to_string(id), Role::kZone, ShapeKind::kBox,
                                Vec3(hx, hy, kPadHalfThickness));
    b.object.mass = 0;
    b.object.friction = kZoneFriction;
    b.object.restitution = kZoneRestitution;
    b.object.color = kZoneColour;
    b.pose.position = Vec3(x, y, kPadHalfThickness);
    b.pose.rotation = axis_angle(Vec3::UnitZ(), yaw);
    return add(std::move(b));
  }

  // A static scenery object (table, ramp, container) built from `parts`.
  int add_static(const std::string& name, std::vector<ShapePart> parts, const Pose& pose) {
    BodySpec b;
    b.object.id = next_id();
    b.object.name = name + "_" + std::to_string(b.object.id);
    b.object.role = Role::kOther;
    b.object.mass = 0;
    b.object.friction = kStaticFriction;
    b.object.restitution = kStaticRestitution;
    b.object.color = kStaticColour;
    b.parts = std::move(parts);
    b.pose = pose;
    return add(std::move(b));
  }

  // Random rotation about z only, so a body standing on the floor keeps standing.
  Quat random_yaw() { return axis_angle(Vec3::UnitZ(), rng.uniform(0, 2 * M_PI)); }
};

// Half extents of the body's world bounds at its current pose (how far it reaches from its centre).
Vec3 half_size(const BodySpec& b) {
  const Aabb box = body_aabb(b.parts, b.object.scale, b.pose);
  return 0.5 * (box.max - box.min);
}

ShapePart box_part(const Vec3& half, const Vec3& centre) {
  ShapePart p;
  p.kind = ShapeKind::kBox;
  p.half_extents = half;
  p.local.position = centre;
  return p;
}

}  // namespace

// drop: the target falls from rest onto a floor with the zone; half of the scenes put an
// obstacle under it that deflects it. Outcome: does it land on (or bounce/roll onto) the zone?
namespace drop {
constexpr int kFrames = 60;
constexpr Range kZoneHalf{0.12, 0.22};
constexpr Range kTargetHalf{0.04, 0.09};
constexpr Range kDropHeight{0.4, 0.9};  // bottom of the target above the floor
constexpr Range kOffset{0.0, 0.38};     // horizontal distance from the zone centre
constexpr double kObstacleChance = 0.5;
constexpr Range kObstacleHalf{0.06, 0.13};
constexpr Range kObstacleShift{0.0, 0.8};  // fraction of its half size, random direction
}  // namespace drop

SimSetup make_drop(uint64_t seed) {
  Builder b("drop", seed, drop::kFrames);
  Rng& rng = b.rng;
  b.add_zone(sample(rng, drop::kZoneHalf), sample(rng, drop::kZoneHalf), 0, 0,
             rng.uniform(0, M_PI));
  BodySpec target = b.random_primitive(Role::kTarget, drop::kTargetHalf);
  target.pose.rotation = random_rotation(rng);
  const double offset = sample(rng, drop::kOffset), angle = rng.uniform(0, 2 * M_PI);
  target.pose.position = Vec3(offset * std::cos(angle), offset * std::sin(angle), 0);
  rest_on(target, sample(rng, drop::kDropHeight));
  const Vec3 drop_point = target.pose.position;
  b.add(std::move(target));
  if (rng.uniform() < drop::kObstacleChance) {
    BodySpec obstacle = b.random_primitive(Role::kOther, drop::kObstacleHalf);
    obstacle.pose.rotation = b.random_yaw();
    const double shift = sample(rng, drop::kObstacleShift) * obstacle.object.scale.x();
    const double dir = rng.uniform(0, 2 * M_PI);
    obstacle.pose.position =
        Vec3(drop_point.x() + shift * std::cos(dir), drop_point.y() + shift * std::sin(dir), 0);
    // On the pad where their footprints meet, else on the floor.
    const Aabb zone = body_aabb(b.body(0).parts, b.body(0).object.scale, b.body(0).pose);
    Aabb foot = body_aabb(obstacle.parts, obstacle.object.scale, obstacle.pose);
    const bool on_pad = foot.min.x() < zone.max.x() && foot.max.x() > zone.min.x() &&
                        foot.min.y() < zone.max.y() && foot.max.y() > zone.min.y();
    rest_on(obstacle, on_pad ? 2 * kPadHalfThickness : 0.0);
    b.add(std::move(obstacle));
  }
  return b.setup;
}

// collide: a blue probe slides or rolls into the target resting on the floor; the zone lies
// beyond the target. Outcome: is the target knocked far enough (and straight enough) to reach it?
namespace collide {
constexpr int kFrames = 60;
constexpr Range kTargetHalf{0.04, 0.08};
constexpr Range kProbeHalf{0.04, 0.08};
constexpr Range kZoneHalf{0.08, 0.18};
constexpr Range kZoneGap{0.05, 0.36};  // floor between target and zone along the push
constexpr Range kZoneSide{-0.15, 0.15};
constexpr Range kProbeDistance{0.25, 0.5};  // gap between probe and target
constexpr Range kProbeSpeed{1.5, 4.0};      // m/s
constexpr Range kAimError{-0.06, 0.06};     // lateral aim offset at the target, m
}  // namespace collide

SimSetup make_collide(uint64_t seed) {
  Builder b("collide", seed, collide::kFrames);
  Rng& rng = b.rng;
  BodySpec target = b.random_primitive(Role::kTarget, collide::kTargetHalf);
  target.pose.rotation = b.random_yaw();
  rest_on(target, 0);
  const Vec3 target_half = half_size(target);
  b.add(std::move(target));
  const double hx = sample(rng, collide::kZoneHalf), hy = sample(rng, collide::kZoneHalf);
  b.add_zone(hx, hy, target_half.x() + sample(rng, collide::kZoneGap) + hx,
             sample(rng, collide::kZoneSide), 0);
  BodySpec probe = b.random_primitive(Role::kProbe, collide::kProbeHalf);
  probe.pose.rotation = b.random_yaw();
  const Vec3 probe_half = half_size(probe);
  probe.pose.position =
      Vec3(-(target_half.x() + sample(rng, collide::kProbeDistance) + probe_half.x()), 0, 0);
  rest_on(probe, 0);
  const Vec3 aim(0, sample(rng, collide::kAimError), 0);
  Vec3 dir = aim - probe.pose.position;
  dir.z() = 0;
  probe.linear_velocity = sample(rng, collide::kProbeSpeed) * dir.normalized();
  b.add(std::move(probe));
  return b.setup;
}

// roll: the target starts at rest (or with a small push) on a ramp and rolls or slides down and
// across the floor towards the zone; boxes may stay put on shallow ramps. Outcome: does it
// reach the zone?
namespace roll {
constexpr int kFrames = 90;
constexpr Range kRampAngleDeg{12, 35};
constexpr Range kRampLength{0.5, 0.8};
constexpr double kRampHalfWidth = 0.2;
constexpr Range kStartFraction{0.4, 0.9};           // start position along the slope from its foot
constexpr Range kPushSpeed{0.1, 0.5};               // initial speed down the slope, m/s
constexpr double kPushAngle = 12.0 * M_PI / 180.0;  // push heading off straight down, rad
constexpr Range kTargetHalf{0.04, 0.08};
constexpr double kSphereChance = 0.5;  // else cylinder on its side or box (equally)
constexpr Range kZoneHalf{0.08, 0.18};
constexpr Range kZoneGap{0.1, 1.35};  // floor between the ramp foot and the zone
constexpr Range kZoneSide{-0.25, 0.25};
}  // namespace roll

SimSetup make_roll(uint64_t seed) {
  Builder b("roll", seed, roll::kFrames);
  Rng& rng = b.rng;
  const double theta = sample(rng, roll::kRampAngleDeg) * M_PI / 180.0;
  const double length = sample(rng, roll::kRampLength);
  const double height = length * std::tan(theta);
  ShapePart wedge;
  wedge.kind = ShapeKind::kConvexHull;
  wedge.hull_mesh = make_wedge_mesh(length, height, roll::kRampHalfWidth);
  Pose ramp_pose;
  ramp_pose.position = Vec3(-length, 0, 0);  // the slope's foot is at x = 0
  b.add_static("ramp", {wedge}, ramp_pose);

  const double u = rng.uniform();
  ShapeKind kind = ShapeKind::kSphere;
  if (u >= roll::kSphereChance) {
    kind = u < 0.5 * (1 + roll::kSphereChance) ? ShapeKind::kCylinder : ShapeKind::kBox;
  }
  BodySpec target = b.primitive(Role::kTarget, kind, roll::kTargetHalf);
  // Slope surface z = -x tan(theta) for x in [-length, 0]; n is its outward normal.
  const Vec3 n(std::sin(theta), 0, std::cos(theta));
  const Vec3 down(std::cos(theta), 0, -std::sin(theta));
  const double slope_length = length / std::cos(theta);
  // Keep the whole target over the slope even when it starts near the top.
  const double s = std::min(sample(rng, roll::kStartFraction) * slope_length,
                            slope_length - 1.5 * target.object.scale.maxCoeff());
  const Vec3 contact(-s * std::cos(theta), 0, s * std::sin(theta));
  const Quat tilt = axis_angle(Vec3::UnitY(), theta);
  double lift = target.object.scale.x();  // sphere radius, cylinder radius
  if (kind == ShapeKind::kCylinder) {
    target.pose.rotation = tilt * axis_angle(Vec3::UnitX(), M_PI / 2);  // axis across the slope
  } else if (kind == ShapeKind::kBox) {
    target.pose.rotation = tilt;
    lift = target.object.scale.z();
  }
  target.pose.position = contact + lift * n;
  const Quat heading = axis_angle(n, rng.uniform(-roll::kPushAngle, roll::kPushAngle));
  target.linear_velocity = sample(rng, roll::kPushSpeed) * (heading * down);
  b.add(std::move(target));

  const double hx = sample(rng, roll::kZoneHalf), hy = sample(rng, roll::kZoneHalf);
  b.add_zone(hx, hy, sample(rng, roll::kZoneGap) + hx, sample(rng, roll::kZoneSide), 0);
  return b.setup;
}

// dominoes: a row of 3-6 standing dominoes; the first is tipped over, and the last one (the
// target) falls towards the zone if the chain carries on. Spacing sometimes exceeds a
// domino's height, which stops the chain. Outcome: does the last domino fall onto the zone?
namespace dominoes {
constexpr int kFrames = 90;
constexpr int kMinCount = 3;
constexpr int kMaxCount = 6;
constexpr Range kHalfThickness{0.01, 0.015};
constexpr Range kHalfWidth{0.04, 0.06};
constexpr Range kHalfHeight{0.08, 0.12};
constexpr Range kSpacing{0.6, 1.6};  // centre spacing as a fraction of the domino height
constexpr double kSpacingJitter = 0.1;
constexpr double kSideJitter = 0.01;               // m
constexpr double kYawJitter = 5.0 * M_PI / 180.0;  // rad
constexpr Range kTipRate{3.0, 6.0};                // initial angular speed of the first, rad/s
constexpr Range kZoneHalf{0.08, 0.15};
constexpr Range kZoneGap{0.0, 0.12};  // floor between the last domino and the zone
}  // namespace dominoes

SimSetup make_dominoes(uint64_t seed) {
  Builder b("dominoes", seed, dominoes::kFrames);
  Rng& rng = b.rng;
  const int count = static_cast<int>(rng.uniform_int(dominoes::kMinCount, dominoes::kMaxCount));
  const Vec3 half(sample(rng, dominoes::kHalfThickness), sample(rng, dominoes::kHalfWidth),
                  sample(rng, dominoes::kHalfHeight));
  const double spacing = sample(rng, dominoes::kSpacing) * 2 * half.z();
  const Material& material = b.pick_material();  // one set of dominoes
  double x = 0;
  int first = -1, last = -1;
  for (int i = 0; i < count; ++i) {
    if (i > 0)
      x += spacing * (1 + rng.uniform(-dominoes::kSpacingJitter, dominoes::kSpacingJitter));
    const Role role = i + 1 == count ? Role::kTarget : Role::kOther;
    BodySpec d = b.primitive_with_scale(role, ShapeKind::kBox, half);
    d.object.name = "domino_" + std::to_string(d.object.id);
    Builder::set_material(d, material);
    d.pose.rotation =
        axis_angle(Vec3::UnitZ(), rng.uniform(-dominoes::kYawJitter, dominoes::kYawJitter));
    d.pose.position = Vec3(x, rng.uniform(-dominoes::kSideJitter, dominoes::kSideJitter), 0);
    rest_on(d, 0);
    last = b.add(std::move(d));
    if (i == 0) first = last;
  }
  // Tip the first domino forward about its bottom front edge.
  BodySpec& d0 = b.body(first);
  const double w = sample(rng, dominoes::kTipRate);
  d0.angular_velocity = Vec3(0, w, 0);
  d0.linear_velocity = Vec3(0, w, 0).cross(Vec3(-half.x(), 0, half.z()));
  const double hx = sample(rng, dominoes::kZoneHalf), hy = sample(rng, dominoes::kZoneHalf);
  const double x_last = b.body(last).pose.position.x();
  b.add_zone(hx, hy, x_last + half_size(b.body(last)).x() + sample(rng, dominoes::kZoneGap) + hx,
             b.body(last).pose.position.y(), 0);
  return b.setup;
}

// support: a stack of 2-4 blocks on the floor, each shifted from the one below in one lean
// direction; the red top block may be carried down when the stack topples. The zone lies on the
// floor roughly in the lean direction. Outcome: does the top block hit the zone?
namespace support {
constexpr int kFrames = 60;
constexpr int kMinBlocks = 2;
constexpr int kMaxBlocks = 4;
constexpr Range kBlockHalf{0.04, 0.08};  // half width and depth
constexpr Range kBlockHalfHeight{0.03, 0.06};
constexpr Range kShift{0.2, 1.1};  // shift of each block as a fraction of the half width below
constexpr double kCylinderChance = 0.3;
constexpr double kLeanJitter = 30.0 * M_PI / 180.0;  // zone direction around the lean, rad
constexpr Range kZoneHalf{0.08, 0.15};
constexpr Range kZoneGap{0.0, 0.15};  // floor between the stack base and the zone
}  // namespace support

SimSetup make_support(uint64_t seed) {
  Builder b("support", seed, support::kFrames);
  Rng& rng = b.rng;
  const int count = static_cast<int>(rng.uniform_int(support::kMinBlocks, support::kMaxBlocks));
  const double lean = rng.uniform(0, 2 * M_PI);
  const Vec3 lean_dir(std::cos(lean), std::sin(lean), 0);
  double z = 0;
  Vec3 centre = Vec3::Zero();
  double below_half = 0;
  int base = -1;
  for (int i = 0; i < count; ++i) {
    const Role role = i + 1 == count ? Role::kTarget : Role::kOther;
    const bool cylinder = rng.uniform() < support::kCylinderChance;
    Vec3 half(sample(rng, support::kBlockHalf), sample(rng, support::kBlockHalf),
              sample(rng, support::kBlockHalfHeight));
    if (cylinder) half.y() = half.x();
    BodySpec block =
        b.primitive_with_scale(role, cylinder ? ShapeKind::kCylinder : ShapeKind::kBox, half);
    block.object.name = "block_" + std::to_string(block.object.id);
    block.pose.rotation = axis_angle(Vec3::UnitZ(), lean);
    if (i > 0) centre += sample(rng, support::kShift) * below_half * lean_dir;
    block.pose.position = centre;
    rest_on(block, z);
    z += 2 * half.z();
    below_half = half.x();
    const int index = b.add(std::move(block));
    if (i == 0) base = index;
  }
  const double hx = sample(rng, support::kZoneHalf), hy = sample(rng, support::kZoneHalf);
  const double dir = lean + rng.uniform(-support::kLeanJitter, support::kLeanJitter);
  // Far enough that the pad never touches the base block, whatever its size.
  const double base_reach = half_size(b.body(base)).head<2>().norm();
  const double d = base_reach + sample(rng, support::kZoneGap) + std::hypot(hx, hy);
  b.add_zone(hx, hy, d * std::cos(dir), d * std::sin(dir), dir);
  return b.setup;
}

// contain: a static open box (four walls) with the zone pad as its floor; the target is dropped
// or thrown towards it. Outcome: does the target end up inside, touching the pad?
namespace contain {
constexpr int kFrames = 60;
constexpr Range kInnerHalf{0.1, 0.18};  // inner half width and depth of the container
constexpr Range kWallHeight{0.06, 0.16};
constexpr double kWallHalfThickness = 0.01;
constexpr Range kTargetHalf{0.03, 0.06};
constexpr double kThrowChance = 0.5;  // else dropped from rest above the landing point
constexpr Range kLanding{0.0, 2.1};   // landing point offset as a fraction of the inner half size
constexpr Range kDropHeight{0.25, 0.5};  // bottom of the target above the rim when dropped
constexpr Range kThrowDistance{0.4, 0.7};
constexpr Range kThrowHeight{0.15, 0.4};
constexpr Range kFlightTime{0.35, 0.6};  // s, from release to the rim height
}  // namespace contain

SimSetup make_contain(uint64_t seed) {
  Builder b("contain", seed, contain::kFrames);
  Rng& rng = b.rng;
  const double ix = sample(rng, contain::kInnerHalf), iy = sample(rng, contain::kInnerHalf);
  const double wall_height = sample(rng, contain::kWallHeight);
  const double t = contain::kWallHalfThickness;
  const double hz = 0.5 * wall_height;
  std::vector<ShapePart> walls = {box_part(Vec3(t, iy + 2 * t, hz), Vec3(ix + t, 0, hz)),
                                  box_part(Vec3(t, iy + 2 * t, hz), Vec3(-ix - t, 0, hz)),
                                  box_part(Vec3(ix, t, hz), Vec3(0, iy + t, hz)),
                                  box_part(Vec3(ix, t, hz), Vec3(0, -iy - t, hz))};
  b.add_zone(ix, iy, 0, 0, 0);
  b.add_static("container", std::move(walls), Pose{});

  BodySpec target = b.random_primitive(Role::kTarget, contain::kTargetHalf);
  target.pose.rotation = random_rotation(rng);
  const double along = rng.uniform(0, 2 * M_PI);
  const double landing = sample(rng, contain::kLanding);
  const Vec3 land(landing * ix * std::cos(along), landing * iy * std::sin(along), 0);
  if (rng.uniform() < contain::kThrowChance) {
    const double heading = rng.uniform(0, 2 * M_PI);
    const double dist = sample(rng, contain::kThrowDistance);
    target.pose.position = land - dist * Vec3(std::cos(heading), std::sin(heading), 0);
    rest_on(target, wall_height + sample(rng, contain::kThrowHeight));
    // Ballistic launch that reaches the landing point at rim height after the flight time.
    const double time = sample(rng, contain::kFlightTime);
    const Vec3 delta(land.x() - target.pose.position.x(), land.y() - target.pose.position.y(),
                     wall_height - (target.pose.position.z() - half_size(target).z()));
    target.linear_velocity =
        Vec3(delta.x() / time, delta.y() / time, delta.z() / time + 0.5 * kGravity * time);
  } else {
    target.pose.position = land;
    rest_on(target, wall_height + sample(rng, contain::kDropHeight));
  }
  b.add(std::move(target));
  return b.setup;
}

// link: a chain of 4-7 box links joined by ball joints lies on a table with its free end
// hanging over the edge; the zone is on the floor beyond the edge. Whether the overhang pulls
// the whole chain off depends on how much of it hangs and on friction. The target is the link
// at the table end. Outcome: does the chain slide off and the target land on the zone?
namespace link {
constexpr int kFrames = 90;
constexpr int kMinLinks = 4;
constexpr int kMaxLinks = 7;
constexpr Range kTableHeight{0.2, 0.35};
constexpr double kTableHalfLength = 0.5;
constexpr double kTableHalfWidth = 0.3;
constexpr Range kLinkHalfLength{0.035, 0.055};
constexpr double kLinkHalfWidth = 0.018;
constexpr double kLinkHalfHeight = 0.012;
constexpr Range kOverhang{0.18, 0.75};  // fraction of the chain length past the edge
constexpr Range kZoneHalf{0.1, 0.18};
constexpr Range kZoneGap{0.0, 0.15};  // floor between the table edge and the zone
}  // namespace link

SimSetup make_link(uint64_t seed) {
  Builder b("link", seed, link::kFrames);
  Rng& rng = b.rng;
  const double table_height = sample(rng, link::kTableHeight);
  const double th = 0.5 * table_height;
  b.add_static("table",
               {box_part(Vec3(link::kTableHalfLength, link::kTableHalfWidth, th), Vec3::Zero())},
               Pose{Vec3(-link::kTableHalfLength, 0, th), Quat::Identity()});
  const int count = static_cast<int>(rng.uniform_int(link::kMinLinks, link::kMaxLinks));
  const Vec3 half(sample(rng, link::kLinkHalfLength), link::kLinkHalfWidth, link::kLinkHalfHeight);
  const double chain = 2 * half.x() * count;
  const Material& material = b.pick_material();                       // one chain
  const double start = sample(rng, link::kOverhang) * chain - chain;  // x of the table-end tip
  std::vector<int> links;
  for (int i = 0; i < count; ++i) {
    const Role role = i == 0 ? Role::kTarget : Role::kOther;
    BodySpec l = b.primitive_with_scale(role, ShapeKind::kBox, half);
    l.object.name = "link_" + std::to_string(l.object.id);
    Builder::set_material(l, material);
    l.pose.position = Vec3(start + (2 * i + 1) * half.x(), 0, table_height + half.z());
    links.push_back(b.add(std::move(l)));
  }
  for (int i = 0; i + 1 < count; ++i) {
    b.setup.joints.push_back(
        {links[i], links[i + 1], Vec3(start + 2 * (i + 1) * half.x(), 0, table_height + half.z())});
  }
  const double hx = sample(rng, link::kZoneHalf), hy = sample(rng, link::kZoneHalf);
  b.add_zone(hx, hy, sample(rng, link::kZoneGap) + hx, 0, 0);
  return b.setup;
}

nlohmann::json physion_parameters(const std::string& name) {
  using nlohmann::json;
  json p;
  p["gravity_mps2"] = kGravity;
  p["physics_hz"] = kPhysicsHz;
  p["frame_rate_hz"] = kPhysicsHz / kSubsteps;
  p["floor"] = {{"friction", kFloorFriction}, {"restitution", kFloorRestitution}};
  p["contact_tolerance_m"] = kContactTolerance;
  p["rolling_friction_over_radius"] = kRollingResistance;
  p["static_scenery"] = {{"friction", kStaticFriction}, {"restitution", kStaticRestitution}};
  p["zone"] = {{"half_thickness", kPadHalfThickness},
               {"friction", kZoneFriction},
               {"restitution", kZoneRestitution}};
  json materials;
  for (const Material& m : kMaterials) {
    materials[m.name] = {
        {"density", m.density}, {"friction", m.friction}, {"restitution", m.restitution}};
  }
  p["materials"] = materials;
  if (name == "drop") {
    p["num_frames"] = drop::kFrames;
    p["zone_half"] = to_json(drop::kZoneHalf);
    p["target_half"] = to_json(drop::kTargetHalf);
    p["drop_height"] = to_json(drop::kDropHeight);
    p["offset"] = to_json(drop::kOffset);
    p["obstacle_chance"] = drop::kObstacleChance;
    p["obstacle_half"] = to_json(drop::kObstacleHalf);
    p["obstacle_shift"] = to_json(drop::kObstacleShift);
  } else if (name == "collide") {
    p["num_frames"] = collide::kFrames;
    p["target_half"] = to_json(collide::kTargetHalf);
    p["probe_half"] = to_json(collide::kProbeHalf);
    p["zone_half"] = to_json(collide::kZoneHalf);
    p["zone_gap"] = to_json(collide::kZoneGap);
    p["zone_side"] = to_json(collide::kZoneSide);
    p["probe_distance"] = to_json(collide::kProbeDistance);
    p["probe_speed"] = to_json(collide::kProbeSpeed);
    p["aim_error"] = to_json(collide::kAimError);
  } else if (name == "roll") {
    p["num_frames"] = roll::kFrames;
    p["ramp_angle_deg"] = to_json(roll::kRampAngleDeg);
    p["ramp_length"] = to_json(roll::kRampLength);
    p["ramp_half_width"] = roll::kRampHalfWidth;
    p["start_fraction"] = to_json(roll::kStartFraction);
    p["push_speed"] = to_json(roll::kPushSpeed);
    p["push_angle_rad"] = roll::kPushAngle;
    p["target_half"] = to_json(roll::kTargetHalf);
    p["sphere_chance"] = roll::kSphereChance;
    p["zone_half"] = to_json(roll::kZoneHalf);
    p["zone_gap"] = to_json(roll::kZoneGap);
    p["zone_side"] = to_json(roll::kZoneSide);
  } else if (name == "dominoes") {
    p["num_frames"] = dominoes::kFrames;
    p["count"] = {dominoes::kMinCount, dominoes::kMaxCount};
    p["half_thickness"] = to_json(dominoes::kHalfThickness);
    p["half_width"] = to_json(dominoes::kHalfWidth);
    p["half_height"] = to_json(dominoes::kHalfHeight);
    p["spacing_over_height"] = to_json(dominoes::kSpacing);
    p["spacing_jitter"] = dominoes::kSpacingJitter;
    p["side_jitter"] = dominoes::kSideJitter;
    p["yaw_jitter_rad"] = dominoes::kYawJitter;
    p["tip_rate"] = to_json(dominoes::kTipRate);
    p["zone_half"] = to_json(dominoes::kZoneHalf);
    p["zone_gap"] = to_json(dominoes::kZoneGap);
  } else if (name == "support") {
    p["num_frames"] = support::kFrames;
    p["blocks"] = {support::kMinBlocks, support::kMaxBlocks};
    p["block_half"] = to_json(support::kBlockHalf);
    p["block_half_height"] = to_json(support::kBlockHalfHeight);
    p["shift"] = to_json(support::kShift);
    p["cylinder_chance"] = support::kCylinderChance;
    p["lean_jitter_rad"] = support::kLeanJitter;
    p["zone_half"] = to_json(support::kZoneHalf);
    p["zone_gap"] = to_json(support::kZoneGap);
  } else if (name == "contain") {
    p["num_frames"] = contain::kFrames;
    p["inner_half"] = to_json(contain::kInnerHalf);
    p["wall_height"] = to_json(contain::kWallHeight);
    p["wall_half_thickness"] = contain::kWallHalfThickness;
    p["target_half"] = to_json(contain::kTargetHalf);
    p["throw_chance"] = contain::kThrowChance;
    p["landing"] = to_json(contain::kLanding);
    p["drop_height"] = to_json(contain::kDropHeight);
    p["throw_distance"] = to_json(contain::kThrowDistance);
    p["throw_height"] = to_json(contain::kThrowHeight);
    p["flight_time"] = to_json(contain::kFlightTime);
  } else if (name == "link") {
    p["num_frames"] = link::kFrames;
    p["links"] = {link::kMinLinks, link::kMaxLinks};
    p["table_height"] = to_json(link::kTableHeight);
    p["table_half_size"] = {link::kTableHalfLength, link::kTableHalfWidth};
    p["link_half_length"] = to_json(link::kLinkHalfLength);
    p["link_half_width"] = link::kLinkHalfWidth;
    p["link_half_height"] = link::kLinkHalfHeight;
    p["overhang"] = to_json(link::kOverhang);
    p["zone_half"] = to_json(link::kZoneHalf);
    p["zone_gap"] = to_json(link::kZoneGap);
  } else {
    throw ValueError("scenario", "no Physion-like scenario named '" + name + "'");
  }
  return p;
}

}  // namespace dynscope::sim
