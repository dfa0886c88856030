// Rollout consistency checks.
#include "engine/scene/rollout.h"

#include <cmath>
#include <string>

#include "engine/core/error.h"

namespace dynscope {

namespace {

void check_size(const char* field, size_t got, size_t expected, const char* what) {
  if (got != expected) {
    throw ValueError(field, "has " + std::to_string(got) + " entries, expected " +
                                std::to_string(expected) + " (" + what + ")");
  }
}

}  // namespace

void Rollout::validate() const {
  const auto n = static_cast<size_t>(rest.rows());
  const auto t = static_cast<size_t>(num_frames());
  const auto o = static_cast<size_t>(num_objects());
  check_size("object_ids", object_ids.size(), n, "one per point");
  if (!static_points.empty()) check_size("static_points", static_points.size(), n, "one per point");
  check_size("truth", truth.size(), t, "one per frame");
  check_size("poses", poses.size(), t, "one per frame");
  check_size("point_error", point_error.size(), t, "one per frame");
  check_size("pose_rigid", pose_rigid.size(), o, "one per object");
  if (!contact_distance_truth.empty() || !contact_distance_predicted.empty()) {
    check_size("contact_distance_truth", contact_distance_truth.size(), t, "one per frame");
    check_size("contact_distance_predicted", contact_distance_predicted.size(), t, "one per frame");
  }
  if (observed_frames < 0 || static_cast<size_t>(observed_frames) > t) {
    throw ValueError("observed_frames",
                     std::to_string(observed_frames) + " outside [0, " + std::to_string(t) + "]");
  }
  if (!(dt_s > 0) || !std::isfinite(dt_s)) {
    throw ValueError("dt", "must be positive, got " + std::to_string(dt_s));
  }
  if (!rest.allFinite()) throw ValueError("rest", "non-finite rest coordinate");
  for (size_t f = 0; f < t; ++f) {
    if (static_cast<size_t>(predicted[f].rows()) != n ||
        static_cast<size_t>(truth[f].rows()) != n) {
      throw ValueError("positions", "frame " + std::to_string(f) + " does not have " +
                                        std::to_string(n) + " points");
    }
    if (!predicted[f].allFinite() || !truth[f].allFinite()) {
      throw ValueError("positions", "non-finite position at frame " + std::to_string(f));
    }
    check_size("poses", poses[f].size(), o, "one per object and frame");
  }
  if (faces.rows() > 0 && (faces.minCoeff() < 0 || static_cast<size_t>(faces.maxCoeff()) >= n)) {
    throw ValueError("faces", "index outside [0, " + std::to_string(n) + ")");
  }
}

}  // namespace dynscope
