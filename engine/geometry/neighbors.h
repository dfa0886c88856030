// Neighbour search (exact kd-trees): same-object kNN, other-object kNN within a radius, plain kNN.
#pragma once

#include <cstdint>
#include <vector>

#include "engine/core/types.h"
#include "engine/geometry/kdtree_index.h"

namespace dynscope {

/// `[M,K]` neighbour indices into the source points plus a validity mask. Valid entries of a row
/// come first, sorted by increasing distance (exact, in double; equal distances go to the lower
/// source index), so results equal a brute-force search; masked entries hold index -1. The
/// functions below answer their queries in parallel on compute_threads() threads; the lists do not
/// depend on the thread count.
struct NeighborList {
  IndexMatrix index;
  MaskMatrix mask;

  Eigen::Index rows() const { return index.rows(); }
  Eigen::Index k() const { return index.cols(); }
  /// Number of valid neighbours of query `row`.
  int valid_count(Eigen::Index row) const;
};

/// Every row index of `ids`, ordered by id and, within an id, ascending (a stable sort by id;
/// a counting sort when the ids span a range of at most about twice their number).
std::vector<int32_t> rows_by_id(const std::vector<int32_t>& ids);

/// Exact kd-trees over one set of source points, one per object id, built once and shared by every
/// list whose sources are these points (same-object, other-object, cross-level queries).
class ObjectIndex {
 public:
  /// The source points of one object.
  struct Object {
    int32_t id = 0;
    std::vector<int32_t> global;  ///< Source index of each local point, ascending.
    KdIndex tree;                 ///< Tree over the object's points (local indices).
    Aabb box;                     ///< Bounding box of the object's points.
  };

  /// Indexes `points` `[N,3]` grouped by `ids` `[N]`. Throws ValueError("source_ids") on a size
  /// mismatch and ValueError("source") for a non-finite point.
  ObjectIndex(const Points& points, const std::vector<int32_t>& ids);

  /// Number of indexed source points.
  Eigen::Index size() const { return size_; }
  /// Every object, ascending by id.
  const std::vector<Object>& objects() const { return objects_; }
  /// The object with id `id`, or nullptr when no source point has it.
  const Object* find(int32_t id) const;

 private:
  Eigen::Index size_ = 0;
  std::vector<Object> objects_;
};

/// K nearest source points having the same object id as each query (the query itself included
/// when it is a source point). Rows of objects with fewer than K source points have their
/// remaining entries masked, never padded with duplicates; rows of objects without source points
/// are fully masked. Serves same-level (query == source) and cross-level (down/upsampling)
/// queries. Throws ValueError on size mismatch, k <= 0 or a non-finite point.
NeighborList knn_same_object(const Points& query, const std::vector<int32_t>& query_ids,
                             const Points& source, const std::vector<int32_t>& source_ids, int k);

/// knn_same_object with the queries given by their own index (its points, in its indexing, e.g.
/// a finer level's points asking a coarser level's): the same result, each object's queries
/// answered a leaf of their tree at a time (KdIndex::knn_other). Throws ValueError for k <= 0.
NeighborList knn_same_object(const ObjectIndex& queries, const ObjectIndex& sources, int k);

/// knn_same_object over prebuilt source trees (same result). Throws ValueError on size mismatch,
/// k <= 0 or a non-finite query point.
NeighborList knn_same_object(const Points& query, const std::vector<int32_t>& query_ids,
                             const ObjectIndex& source, int k);

/// K nearest source points whose object id differs from the query's, kept only if within
/// `radius` (Euclidean, inclusive: squared distance <= radius²). Rows with no such point are fully
/// masked. Throws ValueError on size mismatch, k <= 0, a negative or non-finite radius, or a
/// non-finite point.
NeighborList knn_other_objects(const Points& query, const std::vector<int32_t>& query_ids,
                               const Points& source, const std::vector<int32_t>& source_ids, int k,
                               double radius);

/// knn_other_objects over prebuilt source trees (same result). Throws ValueError as above.
NeighborList knn_other_objects(const Points& query, const std::vector<int32_t>& query_ids,
                               const ObjectIndex& source, int k, double radius);

/// K nearest source points regardless of object (the non-object-centric baseline); rows are
/// masked only when there are fewer than K source points. Throws ValueError for k <= 0 or a
/// non-finite point.
NeighborList knn_all(const Points& query, const Points& source, int k);

/// knn_all over a prebuilt source tree (same result). Throws ValueError for k <= 0 or a non-finite
/// query point.
NeighborList knn_all(const Points& query, const KdIndex& source, int k);

}  // namespace dynscope
