// What-if edits of one object's initial state (see initial_state_edit.h).
#include "app/viewer/initial_state_edit.h"

#include <Eigen/Geometry>
#include <cmath>

#include "engine/core/error.h"

namespace dynscope::app::viewer {
namespace {

void check(const Scene& scene, int object, int edit_frame) {
  if (object < 0 || object >= static_cast<int>(scene.objects.size())) {
    throw ValueError("object", std::to_string(object) + " is outside the scene's " +
                                   std::to_string(scene.objects.size()) + " objects");
  }
  if (edit_frame < 1 || edit_frame >= scene.num_frames()) {
    throw ValueError("edit frame", std::to_string(edit_frame) + " is outside 1.." +
                                       std::to_string(scene.num_frames() - 1));
  }
}

// Position and orientation of object `i` at frame `f`: its pose, or its particles' centroid.
Pose state_at(const Scene& scene, int i, int f) {
  const Trajectory& t = scene.trajectories[static_cast<size_t>(i)];
  if (scene.objects[static_cast<size_t>(i)].rigid) return t.poses[static_cast<size_t>(f)];
  Pose p;
  p.position = t.particles[static_cast<size_t>(f)].colwise().mean().transpose();
  return p;
}

Quat from_euler_deg(const Vec3& e) {
  const double k = M_PI / 180.0;
  return Quat(Eigen::AngleAxisd(e.z() * k, Vec3::UnitZ()) *
              Eigen::AngleAxisd(e.y() * k, Vec3::UnitY()) *
              Eigen::AngleAxisd(e.x() * k, Vec3::UnitX()));
}

}  // namespace

ObjectEdit object_initial_state(const Scene& scene, int object, int edit_frame) {
  check(scene, object, edit_frame);
  const Pose now = state_at(scene, object, edit_frame);
  const Pose before = state_at(scene, object, edit_frame - 1);
  ObjectEdit e;
  e.object = object;
  e.position = now.position;
  const Vec3 zyx = now.rotation.toRotationMatrix().eulerAngles(2, 1, 0) * (180.0 / M_PI);
  e.euler_deg = Vec3(zyx.z(), zyx.y(), zyx.x());
  e.velocity = (now.position - before.position) / scene.dt_s;
  return e;
}

Scene apply_initial_state_edit(const Scene& scene, const ObjectEdit& edit, int edit_frame) {
  check(scene, edit.object, edit_frame);
  if (!edit.position.allFinite() || !edit.euler_deg.allFinite() || !edit.velocity.allFinite()) {
    throw ValueError("what-if edit", "position, orientation and velocity must be finite");
  }
  const ObjectEdit old = object_initial_state(scene, edit.object, edit_frame);
  const Pose anchor = state_at(scene, edit.object, edit_frame);
  const Quat turn = (from_euler_deg(edit.euler_deg) * anchor.rotation.conjugate()).normalized();
  const Vec3 extra_velocity = edit.velocity - turn * old.velocity;
  Scene out = scene;
  Trajectory& t = out.trajectories[static_cast<size_t>(edit.object)];
  const bool rigid = scene.objects[static_cast<size_t>(edit.object)].rigid;
  for (int f = 0; f <= edit_frame; ++f) {
    const Vec3 shift = edit.position + extra_velocity * ((f - edit_frame) * scene.dt_s);
    auto move = [&](const Vec3& p) -> Vec3 { return turn * (p - anchor.position) + shift; };
    if (rigid) {
      Pose& p = t.poses[static_cast<size_t>(f)];
      p.position = move(p.position);
      p.rotation = (turn * p.rotation).normalized();
    } else {
      Points& particles = t.particles[static_cast<size_t>(f)];
      for (Eigen::Index r = 0; r < particles.rows(); ++r) {
        particles.row(r) = move(particles.row(r).transpose()).transpose();
      }
    }
  }
  out.validate();
  return out;
}

}  // namespace dynscope::app::viewer
