// Rollout metrics.
#include "engine/rollout/metrics.h"

#include <cmath>
#include <limits>
#include <string>

#include "engine/core/error.h"

namespace dynscope {

double mean_point_error(const Points& a, const Points& b) {
  if (a.rows() != b.rows() || a.rows() == 0) {
    throw ValueError("points", "need equal non-zero row counts, got " + std::to_string(a.rows()) +
                                   " and " + std::to_string(b.rows()));
  }
  return (a - b).rowwise().norm().mean();
}

double min_distance(const Points& a, const Points& b) {
  if (a.rows() == 0 || b.rows() == 0) throw ValueError("points", "min_distance of an empty set");
  double best = std::numeric_limits<double>::infinity();
  for (Eigen::Index i = 0; i < a.rows(); ++i) {
    const Eigen::RowVector3d p = a.row(i);
    best = std::min(best, (b.rowwise() - p).rowwise().squaredNorm().minCoeff());
  }
  return std::sqrt(best);
}

Points select_rows(const Points& points, const std::vector<int32_t>& ids, int32_t id) {
  Eigen::Index n = 0;
  for (int32_t v : ids) n += v == id ? 1 : 0;
  Points out(n, 3);
  Eigen::Index r = 0;
  for (size_t i = 0; i < ids.size(); ++i) {
    if (ids[i] == id) out.row(r++) = points.row(static_cast<Eigen::Index>(i));
  }
  return out;
}

bool contact_predicted(const std::vector<double>& distances, double threshold) {
  for (double d : distances) {
    if (d < threshold) return true;
  }
  return false;
}

}  // namespace dynscope
