// Camera: an orbit camera around a target (z up), with pan/zoom, fit-to-bounds and presets.
#pragma once

#include <Eigen/Core>
#include <string>

#include "engine/core/types.h"

namespace dynscope::render {

/// Standard viewpoints: front looks along +y (from -y), side along -x (from +x), top down -z
/// (x right, y up on screen), iso from (+x, -y, +z) at 35.26 degrees elevation.
enum class ViewPreset { kFront, kSide, kTop, kIso };

/// "front", "side", "top" or "iso".
const char* preset_name(ViewPreset preset);
/// Inverse of preset_name; throws ValueError for an unknown name.
ViewPreset parse_preset(const std::string& name);

/// Perspective orbit camera in scene units. The eye sits at target + distance * (cos(pitch)
/// cos(yaw), cos(pitch) sin(yaw), sin(pitch)) with angles in degrees; world z is up on screen.
struct Camera {
  Vec3 target = Vec3::Zero();
  double distance = 10.0;  ///< Eye to target (scene units, > 0).
  double yaw_deg = -45.0;
  double pitch_deg = 35.26;  ///< Elevation in [-90, 90].
  double fov_deg = 40.0;     ///< Vertical field of view.

  /// Eye position (world).
  Vec3 eye() const;
  /// Unit vector from eye towards target.
  Vec3 forward() const;
  /// Unit screen-up vector (perpendicular to forward; +z-ish except looking straight down/up).
  Vec3 up() const;
  /// Unit screen-right vector.
  Vec3 right() const;

  /// World-to-view matrix (OpenGL convention: camera looks down -z).
  Eigen::Matrix4f view_matrix() const;
  /// Perspective projection for `aspect` = width / height; near/far follow the distance.
  Eigen::Matrix4f projection_matrix(double aspect) const;
  /// Pixel coordinates (x right, y down, origin top-left, pixel centres at +0.5) of `world` in a
  /// width x height image; z of the result is the distance in front of the eye (< 0: behind).
  Vec3 project(const Vec3& world, int width, int height) const;

  /// Rotates the eye around the target; pitch is clamped to [-90, 90].
  void orbit(double dyaw_deg, double dpitch_deg);
  /// Moves target and eye in the view plane by fractions of the view height (dx right, dy up).
  void pan(double dx, double dy);
  /// Multiplies the distance by `factor` (> 0; < 1 moves closer); throws ValueError otherwise.
  void zoom(double factor);
  /// Keeps the direction, centres `bounds` and sets the distance so its bounding sphere fills the
  /// view with `margin` (1 = touching) at `aspect`. Empty bounds leave the camera unchanged.
  void fit(const Aabb& bounds, double aspect, double margin = 1.1);
  /// Sets yaw and pitch of the preset (keeps target, distance, fov).
  void set_preset(ViewPreset preset);
  /// Throws ValueError naming the first non-finite or out-of-range field.
  void validate() const;
};

}  // namespace dynscope::render
