// Kubric MOVi-A recipe (and a MOVi-C-like variant with user meshes) as a Bullet setup.
//
// Recipe (Kubric challenges/movi/movi_def_worker.py, MOVi-A):
//   objects      3..10, each a cube, cylinder or sphere (uniform), placed one after the other
//   size         scale s = 0.7 ("small") or 1.4 ("large"); KuBasic shapes span [-1, 1], so the
//                stored mesh is the unit shape of half extent 1 and Object::scale = (s, s, s):
//                a large cube is 2.8 wide, a large sphere has radius 1.4; the collision shape is
//                the same unit shape scaled by s
//   material     rubber: friction 0.8, restitution 0.7, density 1.1; metal: 0.4, 0.3, 2.7
//                (uniform); mass = density * volume of the scaled shape
//   colour       one of the eight CLEVR colours (uniform)
//   floor        implicit plane z = 0, friction 0.3, restitution 0.5 (Bullet multiplies the two
//                bodies' coefficients, as PyBullet does in Kubric)
//   placement    uniform random rotation, then a position uniform in the spawn box
//                [(-5,-5,1),(5,5,5)] shrunk by the rotated object's bounds (Kubric's
//                position_sampler); resampled (rotation and position) until it overlaps no
//                placed object, at most 100 times; an object that still overlaps is left out
//   velocity     U([-4,-4,0],[4,4,0]) - [x, y, 0]: random plus a pull towards the centre
//   physics      240 Hz, gravity 10 m/s² along -z; 24 frames stored at 12 fps (frame 0 is the
//                initial state, then every 20 physics steps)
// MOVi-C-like (`meshes` given): the shape is a uniformly drawn user mesh, centred on its bounds
// and normalised so its largest side spans [-1, 1]; the largest side of the placed object is
// U(0.75, 3.0) (Kubric MOVi-C); collision uses the mesh's convex hull; materials as MOVi-A; mass
// is density times the mesh's enclosed volume (its bounding box's for open meshes).
#include <nlohmann/json.hpp>

#include "engine/core/log.h"
#include "engine/sim/bullet_world.h"
#include "engine/sim/generators.h"

namespace dynscope::sim {
namespace {

constexpr int kMinObjects = 3;
constexpr int kMaxObjects = 10;
constexpr double kSmallScale = 0.7;
constexpr double kLargeScale = 1.4;
constexpr double kMinMeshSize = 0.75;
constexpr double kMaxMeshSize = 3.0;
const Vec3 kSpawnMin(-5, -5, 1);
const Vec3 kSpawnMax(5, 5, 5);
constexpr double kMaxSpeed = 4.0;
constexpr int kPlacementTrials = 100;
constexpr double kGravity = 10.0;
constexpr double kPhysicsHz = 240.0;
constexpr int kSubsteps = 20;
constexpr int kFrames = 24;
constexpr double kFloorFriction = 0.3;
constexpr double kFloorRestitution = 0.5;

struct Material {
  const char* name;
  double friction, restitution, density;
};
constexpr Material kMaterials[] = {{"rubber", 0.8, 0.7, 1.1}, {"metal", 0.4, 0.3, 2.7}};

struct ClevrColour {
  const char* name;
  int r, g, b;
};
constexpr ClevrColour kColours[] = {{"gray", 87, 87, 87},   {"red", 173, 35, 35},
                                    {"blue", 42, 75, 215},  {"green", 29, 105, 20},
                                    {"brown", 129, 74, 25}, {"purple", 129, 38, 192},
                                    {"cyan", 41, 208, 208}, {"yellow", 255, 238, 51}};

struct Primitive {
  const char* name;
  ShapeKind kind;
};
constexpr Primitive kPrimitives[] = {
    {"cube", ShapeKind::kBox}, {"cylinder", ShapeKind::kCylinder}, {"sphere", ShapeKind::kSphere}};

// Centres a user mesh on its bounds and scales it so that its largest side spans [-1, 1].
Mesh normalised_mesh(const Mesh& mesh) {
  const Aabb box = Aabb::of(mesh.vertices);
  const Vec3 centre = 0.5 * (box.min + box.max);
  const double half = 0.5 * (box.max - box.min).maxCoeff();
  Mesh out = mesh;
  out.vertices.rowwise() -= centre.transpose();
  out.vertices /= half;
  return out;
}

}  // namespace

SimSetup make_movi(uint64_t seed, const std::vector<Mesh>& meshes) {
  Rng rng(seed);
  const bool user_meshes = !meshes.empty();
  SimSetup s;
  s.scenario = user_meshes ? "movi-c" : "movi-a";
  s.seed = seed;
  s.gravity = kGravity;
  s.physics_rate_hz = kPhysicsHz;
  s.substeps_per_frame = kSubsteps;
  s.num_frames = kFrames;
  s.floor_friction = kFloorFriction;
  s.floor_restitution = kFloorRestitution;

  std::vector<Mesh> unit_meshes;
  for (const Mesh& m : meshes) unit_meshes.push_back(normalised_mesh(m));

  // Placed objects go into this world only to test new candidates for overlap.
  WorldOptions placement_options;
  placement_options.gravity = kGravity;
  placement_options.physics_dt_s = 1.0 / kPhysicsHz;
  BulletWorld placement(placement_options);

  const auto count = static_cast<int>(rng.uniform_int(kMinObjects, kMaxObjects));
  for (int i = 0; i < count; ++i) {
    const auto id = static_cast<int32_t>(s.bodies.size());
    BodySpec body;
    if (user_meshes) {
      const auto m =
          static_cast<size_t>(rng.uniform_int(0, static_cast<int64_t>(unit_meshes.size()) - 1));
      const double size = rng.uniform(kMinMeshSize, kMaxMeshSize);
      body.object.id = id;
      body.object.name = "mesh" + std::to_string(m) + "_" + std::to_string(id);
      body.object.scale = Vec3::Constant(size / 2.0);
      ShapePart part;
      part.kind = ShapeKind::kConvexHull;
      part.hull_mesh = unit_meshes[m];
      body.parts.push_back(std::move(part));
    } else {
      const Primitive& p = kPrimitives[rng.uniform_int(0, 2)];
      const double scale = rng.uniform_int(0, 1) ? kLargeScale : kSmallScale;
      body = primitive_body(id, std::string(p.name) + "_" + std::to_string(id), Role::kOther,
                            p.kind, Vec3::Constant(scale));
    }
    const ClevrColour& c = kColours[rng.uniform_int(0, 7)];
    body.object.color = srgb_to_linear(Vec3(c.r, c.g, c.b) / 255.0);
    const Material& mat = kMaterials[rng.uniform_int(0, 1)];
    body.object.friction = mat.friction;
    body.object.restitution = mat.restitution;
    set_density(body, mat.density);
    if (!(body.object.mass > 0)) {
      // An open user mesh encloses no definite volume; its bounding box stands in for it.
      const Aabb box = body_aabb(body.parts, body.object.scale, Pose{});
      body.object.mass = mat.density * (box.max - box.min).prod();
    }

    bool placed = false;
    for (int trial = 0; trial < kPlacementTrials && !placed; ++trial) {
      body.pose.rotation = random_rotation(rng);
      body.pose.position.setZero();
      const Aabb box = body_aabb(body.parts, body.object.scale, body.pose);
      // Kubric shrinks the region by the object's bounds; when the object is taller than the
      // region this interval is reversed and the formula still picks a point between its ends.
      const Vec3 lo = kSpawnMin - box.min, hi = kSpawnMax - box.max;
      for (int a = 0; a < 3; ++a) body.pose.position[a] = rng.uniform(lo[a], hi[a]);
      placed = !placement.overlaps(body, 0.0);
    }
    if (!placed) {
      log_debug(s.scenario, " seed ", seed, ": object ", i, " left out, no free spot after ",
                kPlacementTrials, " trials");
      continue;
    }
    placement.add_body(body);
    const Vec3 random_velocity(rng.uniform(-kMaxSpeed, kMaxSpeed),
                               rng.uniform(-kMaxSpeed, kMaxSpeed), 0.0);
    body.linear_velocity =
        random_velocity - Vec3(body.pose.position.x(), body.pose.position.y(), 0.0);
    s.bodies.push_back(std::move(body));
  }
  return s;
}

nlohmann::json movi_parameters(bool user_meshes) {
  nlohmann::json p;
  p["recipe"] =
      user_meshes ? "Kubric MOVi-C-like (user meshes, convex-hull collision)" : "Kubric MOVi-A";
  p["num_objects"] = {kMinObjects, kMaxObjects};
  if (user_meshes) {
    p["largest_side"] = {kMinMeshSize, kMaxMeshSize};
  } else {
    p["shapes"] = {"cube", "cylinder", "sphere"};
    p["unit_shape_half_extent"] = 1.0;
    p["scales"] = {kSmallScale, kLargeScale};
  }
  nlohmann::json materials;
  for (const Material& m : kMaterials) {
    materials[m.name] = {
        {"friction", m.friction}, {"restitution", m.restitution}, {"density", m.density}};
  }
  p["materials"] = materials;
  p["floor"] = {{"friction", kFloorFriction}, {"restitution", kFloorRestitution}};
  p["spawn_region"] = {{kSpawnMin.x(), kSpawnMin.y(), kSpawnMin.z()},
                       {kSpawnMax.x(), kSpawnMax.y(), kSpawnMax.z()}};
  p["velocity"] = "U([-4,-4,0],[4,4,0]) - [x,y,0]";
  p["gravity_mps2"] = kGravity;
  p["physics_hz"] = kPhysicsHz;
  p["frame_rate_hz"] = kPhysicsHz / kSubsteps;
  p["num_frames"] = kFrames;
  return p;
}

}  // namespace dynscope::sim
