// The per-point state a dynamics model reads at time t (plain data, no torch).
#pragma once

#include <cstdint>
#include <vector>

#include "engine/core/types.h"

namespace dynscope {

/// Positions p(t) and the two most recent velocities of N points, with each point's object id.
/// Velocities are per frame (scene units per frame): v(t) = p(t) − p(t−1).
struct PointState {
  Points position = Points(0, 3);       ///< `[N,3]` p(t), world frame.
  Points velocity = Points(0, 3);       ///< `[N,3]` v(t).
  Points prev_velocity = Points(0, 3);  ///< `[N,3]` v(t−1).
  std::vector<int32_t> object_ids;      ///< `[N]` object id of each point.
  Faces faces = Faces(0, 3);  ///< `[F,3]` triangles over the points (mesh input only; else empty).
  /// `[N]` 1 for points of static bodies (ScenePointCloud::static_mask), or empty when unknown. A
  /// model configured with hold_static leaves these points where they are.
  std::vector<uint8_t> static_points;

  Eigen::Index size() const { return position.rows(); }

  /// Builds the state from three consecutive frames of positions; throws ValueError if the row
  /// counts or the id count differ.
  static PointState from_positions(const Points& p_t, const Points& p_tm1, const Points& p_tm2,
                                   const std::vector<int32_t>& object_ids);

  /// Throws ValueError("point_state", ...) on inconsistent sizes, no points, or non-finite values.
  void validate() const;
};

}  // namespace dynscope
