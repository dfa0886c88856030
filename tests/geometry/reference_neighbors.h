// Brute-force neighbour search: the reference the kd-tree results are checked and timed against.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "engine/core/types.h"
#include "engine/geometry/neighbors.h"

namespace dynscope::reference {

/// Which source points a query may take as neighbours.
enum class Relation { kAll, kSameObject, kOtherObject };

/// Squared distance in double, summed x, y, z, as the engine does (so exact ties agree).
inline double squared_distance(const Eigen::RowVector3d& a, const Eigen::RowVector3d& b) {
  const double dx = a.x() - b.x(), dy = a.y() - b.y(), dz = a.z() - b.z();
  return dx * dx + dy * dy + dz * dz;
}

/// Scans every source point for every query: the K nearest allowed points sorted by (squared
/// distance, index), kept only if squared distance <= radius² (pass a negative radius for none).
/// `query_ids` / `source_ids` may be empty for Relation::kAll.
inline NeighborList brute_force_knn(const Points& query, const std::vector<int32_t>& query_ids,
                                    const Points& source, const std::vector<int32_t>& source_ids,
                                    int k, Relation relation, double radius = -1.0) {
  NeighborList out;
  out.index = IndexMatrix::Constant(query.rows(), k, -1);
  out.mask = MaskMatrix::Zero(query.rows(), k);
  std::vector<std::pair<double, int32_t>> candidates;
  for (Eigen::Index i = 0; i < query.rows(); ++i) {
    candidates.clear();
    for (Eigen::Index j = 0; j < source.rows(); ++j) {
      if (relation == Relation::kSameObject && source_ids[j] != query_ids[i]) continue;
      if (relation == Relation::kOtherObject && source_ids[j] == query_ids[i]) continue;
      const double d = squared_distance(query.row(i), source.row(j));
      if (radius >= 0.0 && d > radius * radius) continue;
      candidates.emplace_back(d, static_cast<int32_t>(j));
    }
    // Pairs order by (distance, index): the documented tie rule.
    const size_t keep = std::min(candidates.size(), static_cast<size_t>(k));
    std::partial_sort(candidates.begin(), candidates.begin() + static_cast<std::ptrdiff_t>(keep),
                      candidates.end());
    for (size_t c = 0; c < keep; ++c) {
      out.index(i, static_cast<Eigen::Index>(c)) = candidates[c].second;
      out.mask(i, static_cast<Eigen::Index>(c)) = 1;
    }
  }
  return out;
}

}  // namespace dynscope::reference
