// Bullet dynamics world wrapper: shapes from ShapePart lists, fixed stepping, contact queries.
#include "engine/sim/bullet_world.h"

#include <BulletCollision/NarrowPhaseCollision/btGjkEpaPenetrationDepthSolver.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkPairDetector.h>
#include <BulletCollision/NarrowPhaseCollision/btVoronoiSimplexSolver.h>
#include <LinearMath/btConvexHullComputer.h>
#include <btBulletCollisionCommon.h>
#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "engine/core/error.h"

namespace dynscope {
namespace {

// Bullet rounds box and cylinder edges by the collision margin (and grows hulls by it), so the
// stored mesh would poke out of the collision shape by up to 0.73 margins at corners; a margin of
// 0.5 % of the part's smallest half size keeps that below 0.4 % (Bullet's default is 0.04).
constexpr double kMarginFraction = 0.005;
constexpr double kMinMargin = 1e-4;
constexpr double kDefaultMargin = 0.04;
constexpr int kMaxSatHullPoints = 64;

btVector3 to_bt(const Vec3& v) {
  return btVector3(btScalar(v.x()), btScalar(v.y()), btScalar(v.z()));
}

Vec3 from_bt(const btVector3& v) { return Vec3(v.x(), v.y(), v.z()); }

btTransform to_bt(const Pose& pose) {
  const Quat q = pose.rotation.normalized();
  return btTransform(
      btQuaternion(btScalar(q.x()), btScalar(q.y()), btScalar(q.z()), btScalar(q.w())),
      to_bt(pose.position));
}

Pose from_bt(const btTransform& t) {
  const btQuaternion q = t.getRotation();
  Pose pose;
  pose.position = from_bt(t.getOrigin());
  pose.rotation = Quat(q.w(), q.x(), q.y(), q.z()).normalized();
  return pose;
}

std::string body_name(const BodySpec& body) {
  return "body " + std::to_string(body.object.id) + " (" + body.object.name + ")";
}

// Smallest half size of a scaled part, which bounds how large its margin may be.
double smallest_half_size(const ShapePart& p) {
  if (p.kind != ShapeKind::kConvexHull) {
    return p.kind == ShapeKind::kSphere ? p.half_extents.x() : p.half_extents.minCoeff();
  }
  const Aabb box = Aabb::of(p.hull_mesh.vertices);
  return 0.5 * (box.max - box.min).minCoeff();
}

// Distance between two convex shapes (negative when they overlap): GJK, with EPA for overlaps.
double convex_distance(const btConvexShape* a, const btTransform& ta, const btConvexShape* b,
                       const btTransform& tb) {
  struct Closest : btDiscreteCollisionDetectorInterface::Result {
    double distance = std::numeric_limits<double>::infinity();
    void setShapeIdentifiersA(int, int) override {}
    void setShapeIdentifiersB(int, int) override {}
    void addContactPoint(const btVector3&, const btVector3&, btScalar depth) override {
      distance = std::min(distance, double(depth));
    }
  } closest;
  btVoronoiSimplexSolver simplex;
  btGjkEpaPenetrationDepthSolver epa;
  btGjkPairDetector gjk(a, b, &simplex, &epa);
  btGjkPairDetector::ClosestPointInput input;
  input.m_transformA = ta;
  input.m_transformB = tb;
  gjk.getClosestPoints(input, closest, nullptr);
  return closest.distance;
}

// Distance between two shapes that are convex or compounds of convex children.
double shape_distance(const btCollisionShape* a, const btTransform& ta, const btCollisionShape* b,
                      const btTransform& tb) {
  double d = std::numeric_limits<double>::infinity();
  if (a->isCompound()) {
    const auto* c = static_cast<const btCompoundShape*>(a);
    for (int i = 0; i < c->getNumChildShapes(); ++i) {
      d = std::min(d, shape_distance(c->getChildShape(i), ta * c->getChildTransform(i), b, tb));
    }
    return d;
  }
  if (b->isCompound()) return shape_distance(b, tb, a, ta);
  return convex_distance(static_cast<const btConvexShape*>(a), ta,
                         static_cast<const btConvexShape*>(b), tb);
}

}  // namespace

struct BulletWorld::Impl {
  WorldOptions options;
  btDefaultCollisionConfiguration config;
  btCollisionDispatcher dispatcher{&config};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world{&dispatcher, &broadphase, &solver, &config};
  std::vector<std::unique_ptr<btCollisionShape>> shapes;
  std::vector<std::unique_ptr<btRigidBody>> bodies;
  std::unique_ptr<btRigidBody> floor;
  std::vector<std::unique_ptr<btTypedConstraint>> joints;

  ~Impl() {
    for (auto& j : joints) world.removeConstraint(j.get());
    for (auto& b : bodies) world.removeRigidBody(b.get());
    if (floor) world.removeRigidBody(floor.get());
  }

  // Builds the collision shape of `body`, owned by `owner` (with a compound's children); compound
  // when it has several parts or an offset part.
  static btCollisionShape* make_shape(const BodySpec& body,
                                      std::vector<std::unique_ptr<btCollisionShape>>& owner) {
    const std::string what = body_name(body);
    if (body.parts.empty()) throw ValueError(what, "has no shape parts");
    std::vector<ShapePart> parts;
    for (const ShapePart& raw : body.parts) {
      check_part(raw, body.object.scale, what);
      parts.push_back(scaled_part(raw, body.object.scale));
    }
    auto primitive = [&](const ShapePart& p) -> btCollisionShape* {
      double margin = body.collision_margin;
      if (margin < 0) {
        margin = std::clamp(kMarginFraction * smallest_half_size(p), kMinMargin, kDefaultMargin);
      }
      std::unique_ptr<btConvexShape> shape;
      switch (p.kind) {
        case ShapeKind::kBox:
          shape = std::make_unique<btBoxShape>(to_bt(p.half_extents));
          break;
        case ShapeKind::kSphere:
          shape = std::make_unique<btSphereShape>(btScalar(p.half_extents.x()));
          break;
        case ShapeKind::kCylinder:
          shape = std::make_unique<btCylinderShapeZ>(to_bt(p.half_extents));
          break;
        case ShapeKind::kConvexHull: {
          // Only the hull's corners matter; dropping interior and coplanar mesh vertices keeps
          // the support-point search short for dense user meshes.
          btConvexHullComputer computer;
          computer.compute(p.hull_mesh.vertices.data(), 3 * sizeof(double),
                           static_cast<int>(p.hull_mesh.vertices.rows()), 0, 0);
          if (computer.vertices.size() == 0) throw ValueError(what, "convex hull is empty");
          auto hull = std::make_unique<btConvexHullShape>();
          for (int i = 0; i < computer.vertices.size(); ++i) {
            hull->addPoint(computer.vertices[i], false);
          }
          hull->recalcLocalAabb();
          // Face data lets Bullet clip polytope contacts (SAT) instead of relying on GJK/EPA;
          // SAT costs grow with faces squared, so dense hulls (user meshes) keep GJK/EPA.
          if (hull->getNumPoints() <= kMaxSatHullPoints) hull->initializePolyhedralFeatures();
          shape = std::move(hull);
          break;
        }
      }
      // A sphere's margin is its radius; boxes and cylinders keep their outer size (Bullet moves
      // the implicit dimensions inwards); hulls grow by the (small) margin.
      if (p.kind != ShapeKind::kSphere) shape->setMargin(btScalar(margin));
      owner.push_back(std::move(shape));
      return owner.back().get();
    };
    const bool single = parts.size() == 1 && parts[0].local.position.isZero(0) &&
                        parts[0].local.rotation.isApprox(Quat::Identity(), 0);
    if (single) return primitive(parts[0]);
    auto compound = std::make_unique<btCompoundShape>();
    for (const ShapePart& p : parts) compound->addChildShape(to_bt(p.local), primitive(p));
    owner.push_back(std::move(compound));
    return owner.back().get();
  }
};

BulletWorld::BulletWorld(const WorldOptions& options) : impl_(std::make_unique<Impl>()) {
  if (!(options.physics_dt_s > 0) || !std::isfinite(options.physics_dt_s)) {
    throw ValueError("physics_dt_s",
                     "must be positive, got " + std::to_string(options.physics_dt_s));
  }
  if (!std::isfinite(options.gravity)) throw ValueError("gravity", "must be finite");
  impl_->options = options;
  impl_->world.setGravity(btVector3(0, 0, btScalar(-options.gravity)));
  // Exact separating-axis tests between convex hulls (EPA picks poor normals for aligned faces).
  impl_->world.getDispatchInfo().m_enableSatConvex = true;
  if (options.floor) {
    auto plane = std::make_unique<btStaticPlaneShape>(btVector3(0, 0, 1), btScalar(0));
    btRigidBody::btRigidBodyConstructionInfo info(0, nullptr, plane.get());
    info.m_friction = btScalar(options.floor_friction);
    info.m_restitution = btScalar(options.floor_restitution);
    impl_->floor = std::make_unique<btRigidBody>(info);
    impl_->shapes.push_back(std::move(plane));
    impl_->world.addRigidBody(impl_->floor.get());
  }
}

BulletWorld::~BulletWorld() = default;

int BulletWorld::add_body(const BodySpec& body) {
  const std::string what = body_name(body);
  const Object& o = body.object;
  if (!(o.mass >= 0) || !std::isfinite(o.mass)) throw ValueError(what, "mass must be >= 0");
  if (!(o.friction >= 0) || !std::isfinite(o.friction)) {
    throw ValueError(what, "friction must be >= 0");
  }
  if (!(o.restitution >= 0 && o.restitution <= 1)) {
    throw ValueError(what, "restitution must be in [0, 1]");
  }
  if (!body.pose.position.allFinite() || !body.pose.rotation.coeffs().allFinite() ||
      !body.linear_velocity.allFinite() || !body.angular_velocity.allFinite()) {
    throw ValueError(what, "initial pose or velocity is not finite");
  }
  btCollisionShape* shape = Impl::make_shape(body, impl_->shapes);
  btVector3 inertia(0, 0, 0);
  if (o.mass > 0) shape->calculateLocalInertia(btScalar(o.mass), inertia);
  btRigidBody::btRigidBodyConstructionInfo info(btScalar(o.mass), nullptr, shape, inertia);
  info.m_startWorldTransform = to_bt(body.pose);
  info.m_friction = btScalar(o.friction);
  info.m_restitution = btScalar(o.restitution);
  info.m_rollingFriction = btScalar(body.rolling_friction);
  auto rb = std::make_unique<btRigidBody>(info);
  if (o.mass > 0) {
    rb->setLinearVelocity(to_bt(body.linear_velocity));
    rb->setAngularVelocity(to_bt(body.angular_velocity));
  }
  impl_->world.addRigidBody(rb.get());
  impl_->bodies.push_back(std::move(rb));
  return static_cast<int>(impl_->bodies.size()) - 1;
}

void BulletWorld::add_ball_joint(int a, int b, const Vec3& pivot) {
  const int n = num_bodies();
  if (a < 0 || a >= n || b < 0 || b >= n || a == b) {
    throw ValueError("ball joint", "bodies " + std::to_string(a) + " and " + std::to_string(b) +
                                       " must be two distinct indices below " + std::to_string(n));
  }
  btRigidBody& ra = *impl_->bodies[static_cast<size_t>(a)];
  btRigidBody& rb = *impl_->bodies[static_cast<size_t>(b)];
  const btVector3 p = to_bt(pivot);
  auto joint = std::make_unique<btPoint2PointConstraint>(
      ra, rb, ra.getWorldTransform().inverse() * p, rb.getWorldTransform().inverse() * p);
  impl_->world.addConstraint(joint.get(), /*disableCollisionsBetweenLinkedBodies=*/true);
  impl_->joints.push_back(std::move(joint));
}

bool BulletWorld::overlaps(const BodySpec& body, double tolerance) const {
  struct Callback : btCollisionWorld::ContactResultCallback {
    double tolerance = 0;
    bool hit = false;
    btScalar addSingleResult(btManifoldPoint& cp, const btCollisionObjectWrapper*, int, int,
                             const btCollisionObjectWrapper*, int, int) override {
      if (cp.getDistance() <= tolerance) hit = true;
      return 0;
    }
  } callback;
  callback.tolerance = tolerance;
  callback.m_closestDistanceThreshold = btScalar(std::max(0.0, tolerance));
  std::vector<std::unique_ptr<btCollisionShape>> probe_shapes;
  btCollisionObject probe;
  probe.setCollisionShape(Impl::make_shape(body, probe_shapes));
  probe.setWorldTransform(to_bt(body.pose));
  impl_->world.contactTest(&probe, callback);
  return callback.hit;
}

void BulletWorld::detect_contacts() { impl_->world.performDiscreteCollisionDetection(); }

void BulletWorld::step() { impl_->world.stepSimulation(btScalar(impl_->options.physics_dt_s), 0); }

int BulletWorld::num_bodies() const { return static_cast<int>(impl_->bodies.size()); }

Pose BulletWorld::pose(int i) const {
  return from_bt(impl_->bodies.at(static_cast<size_t>(i))->getWorldTransform());
}

Vec3 BulletWorld::linear_velocity(int i) const {
  return from_bt(impl_->bodies.at(static_cast<size_t>(i))->getLinearVelocity());
}

double BulletWorld::distance(int a, int b) const {
  const btCollisionObject* oa = impl_->bodies.at(static_cast<size_t>(a)).get();
  const btCollisionObject* ob = impl_->bodies.at(static_cast<size_t>(b)).get();
  return shape_distance(oa->getCollisionShape(), oa->getWorldTransform(), ob->getCollisionShape(),
                        ob->getWorldTransform());
}

bool BulletWorld::in_contact(int a, int b, double tolerance) const {
  const btCollisionObject* oa = impl_->bodies.at(static_cast<size_t>(a)).get();
  const btCollisionObject* ob = impl_->bodies.at(static_cast<size_t>(b)).get();
  btCollisionDispatcher& d = impl_->dispatcher;
  for (int m = 0; m < d.getNumManifolds(); ++m) {
    const btPersistentManifold* manifold = d.getManifoldByIndexInternal(m);
    const btCollisionObject* o0 = manifold->getBody0();
    const btCollisionObject* o1 = manifold->getBody1();
    if (!((o0 == oa && o1 == ob) || (o0 == ob && o1 == oa))) continue;
    for (int c = 0; c < manifold->getNumContacts(); ++c) {
      if (manifold->getContactPoint(c).getDistance() <= tolerance) return true;
    }
  }
  // Bullet's box-box detector adds no point until boxes actually penetrate, so a box resting
  // exactly on a box has an empty manifold; measure the gap directly when the bounds are close.
  btVector3 min_a, max_a, min_b, max_b;
  oa->getCollisionShape()->getAabb(oa->getWorldTransform(), min_a, max_a);
  ob->getCollisionShape()->getAabb(ob->getWorldTransform(), min_b, max_b);
  const auto t = static_cast<btScalar>(tolerance);
  const btVector3 pad(t, t, t);
  if (!TestAabbAgainstAabb2(min_a - pad, max_a + pad, min_b, max_b)) return false;
  return distance(a, b) <= tolerance;
}

double BulletWorld::max_penetration() const {
  double deepest = 0;
  btCollisionDispatcher& d = impl_->dispatcher;
  for (int m = 0; m < d.getNumManifolds(); ++m) {
    const btPersistentManifold* manifold = d.getManifoldByIndexInternal(m);
    for (int c = 0; c < manifold->getNumContacts(); ++c) {
      deepest = std::max(deepest, -double(manifold->getContactPoint(c).getDistance()));
    }
  }
  return deepest;
}

}  // namespace dynscope
