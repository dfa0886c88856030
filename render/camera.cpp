// Orbit camera maths: spherical eye placement, look-at and perspective matrices (z up).
#include "render/camera.h"

#include <algorithm>
#include <cmath>

#include "engine/core/error.h"

namespace dynscope::render {
namespace {

constexpr double kPi = 3.14159265358979323846;
double radians(double deg) { return deg * kPi / 180.0; }

}  // namespace

const char* preset_name(ViewPreset preset) {
  switch (preset) {
    case ViewPreset::kFront:
      return "front";
    case ViewPreset::kSide:
      return "side";
    case ViewPreset::kTop:
      return "top";
    case ViewPreset::kIso:
      return "iso";
  }
  return "iso";
}

ViewPreset parse_preset(const std::string& name) {
  for (ViewPreset p : {ViewPreset::kFront, ViewPreset::kSide, ViewPreset::kTop, ViewPreset::kIso}) {
    if (name == preset_name(p)) return p;
  }
  throw ValueError("camera preset", "'" + name + "' is not one of front, side, top, iso");
}

Vec3 Camera::eye() const { return target - distance * forward(); }

Vec3 Camera::forward() const {
  const double y = radians(yaw_deg), p = radians(pitch_deg);
  return -Vec3(std::cos(p) * std::cos(y), std::cos(p) * std::sin(y), std::sin(p));
}

Vec3 Camera::up() const {
  // Derivative of the eye direction with respect to pitch: always perpendicular to the view
  // direction and well defined when looking straight down (top view).
  const double y = radians(yaw_deg), p = radians(pitch_deg);
  return Vec3(-std::sin(p) * std::cos(y), -std::sin(p) * std::sin(y), std::cos(p));
}

Vec3 Camera::right() const { return forward().cross(up()).normalized(); }

Eigen::Matrix4f Camera::view_matrix() const {
  const Vec3 f = forward(), u = up(), r = right(), e = eye();
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.block<1, 3>(0, 0) = r.transpose();
  m.block<1, 3>(1, 0) = u.transpose();
  m.block<1, 3>(2, 0) = -f.transpose();
  m(0, 3) = -r.dot(e);
  m(1, 3) = -u.dot(e);
  m(2, 3) = f.dot(e);
  return m.cast<float>();
}

Eigen::Matrix4f Camera::projection_matrix(double aspect) const {
  // Near/far scale with the distance so depth precision follows the zoom level.
  const double n = std::max(distance * 0.01, 1e-4);
  const double f = distance * 100.0 + 1.0;
  const double t = 1.0 / std::tan(radians(fov_deg) / 2.0);
  Eigen::Matrix4d m = Eigen::Matrix4d::Zero();
  m(0, 0) = t / aspect;
  m(1, 1) = t;
  m(2, 2) = -(f + n) / (f - n);
  m(2, 3) = -2.0 * f * n / (f - n);
  m(3, 2) = -1.0;
  return m.cast<float>();
}

Vec3 Camera::project(const Vec3& world, int width, int height) const {
  const Eigen::Vector4d view =
      view_matrix().cast<double>() * Eigen::Vector4d(world.x(), world.y(), world.z(), 1.0);
  const Eigen::Vector4d clip =
      projection_matrix(static_cast<double>(width) / height).cast<double>() * view;
  const double x_ndc = clip.x() / clip.w(), y_ndc = clip.y() / clip.w();
  return Vec3((x_ndc * 0.5 + 0.5) * width, (0.5 - y_ndc * 0.5) * height, -view.z());
}

void Camera::orbit(double dyaw_deg, double dpitch_deg) {
  yaw_deg = std::remainder(yaw_deg + dyaw_deg, 360.0);
  pitch_deg = std::clamp(pitch_deg + dpitch_deg, -90.0, 90.0);
}

void Camera::pan(double dx, double dy) {
  const double view_height = 2.0 * distance * std::tan(radians(fov_deg) / 2.0);
  target += (dx * right() + dy * up()) * view_height;
}

void Camera::zoom(double factor) {
  if (!(factor > 0.0) || !std::isfinite(factor)) {
    throw ValueError("zoom factor", std::to_string(factor) + " must be > 0");
  }
  distance = std::max(distance * factor, 1e-6);
}

void Camera::fit(const Aabb& bounds, double aspect, double margin) {
  if (bounds.empty()) return;
  target = 0.5 * (bounds.min + bounds.max);
  const double radius = std::max(0.5 * (bounds.max - bounds.min).norm(), 1e-3);
  // The sphere must fit both the vertical and the horizontal field of view.
  const double half_v = radians(fov_deg) / 2.0;
  const double half_h = std::atan(std::tan(half_v) * aspect);
  distance = margin * radius / std::sin(std::min(half_v, half_h));
}

void Camera::set_preset(ViewPreset preset) {
  switch (preset) {
    case ViewPreset::kFront:
      yaw_deg = -90.0;
      pitch_deg = 0.0;
      break;
    case ViewPreset::kSide:
      yaw_deg = 0.0;
      pitch_deg = 0.0;
      break;
    case ViewPreset::kTop:
      yaw_deg = -90.0;
      pitch_deg = 90.0;
      break;
    case ViewPreset::kIso:
      yaw_deg = -45.0;
      pitch_deg = 35.26;
      break;
  }
}

void Camera::validate() const {
  if (!target.allFinite()) throw ValueError("camera.target", "must be finite");
  if (!(distance > 0.0) || !std::isfinite(distance)) {
    throw ValueError("camera.distance", std::to_string(distance) + " must be > 0");
  }
  if (!std::isfinite(yaw_deg)) throw ValueError("camera.yaw", "must be finite");
  if (!(pitch_deg >= -90.0 && pitch_deg <= 90.0)) {
    throw ValueError("camera.pitch", std::to_string(pitch_deg) + " is outside [-90, 90]");
  }
  if (!(fov_deg > 1.0 && fov_deg < 170.0)) {
    throw ValueError("camera.fov", std::to_string(fov_deg) + " is outside (1, 170) degrees");
  }
}

}  // namespace dynscope::render
