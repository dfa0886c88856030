// Neighbour search (PCL kd-trees): same-object kNN, other-object kNN within a radius, plain kNN.
#pragma once

#include <cstdint>
#include <vector>

#include "engine/core/types.h"

namespace dynscope {

/// `[M,K]` neighbour indices into the source points plus a validity mask. Valid entries of a row
/// come first, sorted by increasing distance (exact, in double; equal distances go to the lower
/// source index), so results equal a brute-force search; masked entries hold index -1.
struct NeighborList {
  IndexMatrix index;
  MaskMatrix mask;

  Eigen::Index rows() const { return index.rows(); }
  Eigen::Index k() const { return index.cols(); }
  /// Number of valid neighbours of query `row`.
  int valid_count(Eigen::Index row) const;
};

/// K nearest source points having the same object id as each query (the query itself included
/// when it is a source point). Rows of objects with fewer than K source points have their
/// remaining entries masked, never padded with duplicates; rows of objects without source points
/// are fully masked. Serves same-level (query == source) and cross-level (down/upsampling)
/// queries. Throws ValueError on size mismatch, k <= 0 or a non-finite point.
NeighborList knn_same_object(const Points& query, const std::vector<int32_t>& query_ids,
                             const Points& source, const std::vector<int32_t>& source_ids, int k);

/// K nearest source points whose object id differs from the query's, kept only if within
/// `radius` (Euclidean, inclusive: squared distance <= radius²). Rows with no such point are fully
/// masked. Throws ValueError on size mismatch, k <= 0, a negative or non-finite radius, or a
/// non-finite point.
NeighborList knn_other_objects(const Points& query, const std::vector<int32_t>& query_ids,
                               const Points& source, const std::vector<int32_t>& source_ids, int k,
                               double radius);

/// K nearest source points regardless of object (the non-object-centric baseline); rows are
/// masked only when there are fewer than K source points. Throws ValueError for k <= 0 or a
/// non-finite point.
NeighborList knn_all(const Points& query, const Points& source, int k);

}  // namespace dynscope
