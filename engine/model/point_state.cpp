// PointState construction and checks.
#include "engine/model/point_state.h"

#include <string>

#include "engine/core/error.h"

namespace dynscope {

PointState PointState::from_positions(const Points& p_t, const Points& p_tm1, const Points& p_tm2,
                                      const std::vector<int32_t>& object_ids) {
  if (p_tm1.rows() != p_t.rows() || p_tm2.rows() != p_t.rows()) {
    throw ValueError("point_state",
                     "frames have different point counts: " + std::to_string(p_t.rows()) + ", " +
                         std::to_string(p_tm1.rows()) + ", " + std::to_string(p_tm2.rows()));
  }
  PointState state;
  state.position = p_t;
  state.velocity = p_t - p_tm1;
  state.prev_velocity = p_tm1 - p_tm2;
  state.object_ids = object_ids;
  state.validate();
  return state;
}

void PointState::validate() const {
  const Eigen::Index n = position.rows();
  if (n == 0) throw ValueError("point_state", "no points");
  if (velocity.rows() != n || prev_velocity.rows() != n ||
      static_cast<Eigen::Index>(object_ids.size()) != n) {
    throw ValueError("point_state", "inconsistent sizes: position " + std::to_string(n) +
                                        ", velocity " + std::to_string(velocity.rows()) +
                                        ", prev_velocity " + std::to_string(prev_velocity.rows()) +
                                        ", object_ids " + std::to_string(object_ids.size()));
  }
  if (!static_points.empty() && static_cast<Eigen::Index>(static_points.size()) != n) {
    throw ValueError("point_state", "static_points has " + std::to_string(static_points.size()) +
                                        " entries for " + std::to_string(n) + " points");
  }
  if (faces.size() > 0 && (faces.minCoeff() < 0 || faces.maxCoeff() >= n)) {
    throw ValueError("point_state", "face index out of range [0, " + std::to_string(n) + ")");
  }
  if (!position.allFinite()) throw ValueError("point_state", "position has non-finite values");
  if (!velocity.allFinite() || !prev_velocity.allFinite()) {
    throw ValueError("point_state", "velocity has non-finite values");
  }
}

}  // namespace dynscope
