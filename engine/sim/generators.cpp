// Placement and sampling helpers shared by the scenario generators.
#include "engine/sim/generators.h"

#include <cmath>

namespace dynscope::sim {

Quat random_rotation(Rng& rng) {
  const double u1 = rng.uniform(), u2 = rng.uniform(), u3 = rng.uniform();
  const double a = std::sqrt(1.0 - u1), b = std::sqrt(u1);
  return Quat(b * std::cos(2 * M_PI * u3), a * std::sin(2 * M_PI * u2), a * std::cos(2 * M_PI * u2),
              b * std::sin(2 * M_PI * u3))
      .normalized();
}

Quat axis_angle(const Vec3& axis, double radians) {
  return Quat(Eigen::AngleAxisd(radians, axis.normalized()));
}

Vec3 srgb_to_linear(const Vec3& srgb) {
  Vec3 out;
  for (int i = 0; i < 3; ++i) {
    const double c = srgb[i];
    out[i] = c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
  }
  return out;
}

BodySpec primitive_body(int32_t id, const std::string& name, Role role, ShapeKind kind,
                        const Vec3& scale) {
  BodySpec body;
  body.object.id = id;
  body.object.name = name;
  body.object.role = role;
  body.object.rigid = true;
  body.object.scale = scale;
  ShapePart part;
  part.kind = kind;
  part.half_extents = Vec3::Ones();
  body.parts.push_back(part);
  return body;
}

void set_density(BodySpec& body, double density) {
  body.object.mass = density * body_volume(body.parts, body.object.scale);
}

void rest_on(BodySpec& body, double base_z) {
  const Aabb box = body_aabb(body.parts, body.object.scale, body.pose);
  body.pose.position.z() += base_z - box.min.z();
}

}  // namespace dynscope::sim
