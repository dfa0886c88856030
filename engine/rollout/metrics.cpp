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

int first_contact_frame(const std::vector<double>& distances, double threshold) {
  for (size_t f = 0; f < distances.size(); ++f) {
    if (distances[f] < threshold) return static_cast<int>(f);
  }
  return -1;
}

bool contact_predicted(const std::vector<double>& distances, double threshold) {
  return first_contact_frame(distances, threshold) >= 0;
}

}  // namespace dynscope
