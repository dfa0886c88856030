// Reuse of same-object neighbour lists between the steps of a rollout.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "engine/core/types.h"
#include "engine/geometry/neighbors.h"

namespace dynscope {

/// Keeps the searched same-object lists of a hierarchy (level 0's same list and every coarser
/// level's up list; build_hierarchy takes the others' rows from these) from one step of a rollout
/// to the next. A rigid motion preserves every distance within an object, and the
/// rollout's rigid projection moves each rigid object rigidly at every step, so an object's lists
/// do not change while the points they connect stay the same (at level 0 always; at coarser
/// levels while the voxel grid keeps the same points of the object, as for resting objects).
///
/// The reuse is certified, never assumed. Per list and object the cache fits the rigid motion from
/// the points the list was searched on (its anchor) to the current points and bounds how far any
/// distance can have moved: twice the fit's largest residual, plus the rotation's deviation from
/// an isometry and rounding. A row is reused only when its K+1 nearest distances at the anchor are
/// more than twice that bound apart, so a fresh search would rank them the same: the lists equal a
/// fresh search exactly. Rows with (near-)ties are searched afresh; a list whose object deformed is
/// searched afresh and anchored again; a list whose points are new (a new object, or other points
/// kept by the grid) is searched plainly and anchored when the same points come back at the next
/// step, so lists that change at every step cost no more than without the cache.
///
/// One cache serves one sequence of states (a rollout); it works with any sequence but only saves
/// time when objects move rigidly. Not thread-safe.
class HierarchyCache {
 public:
  /// Rows answered from the cache and rows searched, since construction.
  int64_t reused_rows() const { return reused_rows_; }
  int64_t searched_rows() const { return searched_rows_; }

  /// knn_same_object(query, query_ids, sources, k), reusing certified rows of the list last
  /// computed under the same `slot` (one slot per list of a hierarchy). `query_origin` `[M]` and
  /// `source_origin` `[N]` name each query and source point by a stable index (its level-0 point),
  /// so that a list is only reused between the same points; `source_points` `[N,3]` are the points
  /// `sources` indexes. `queries`, when given, indexes exactly `query` with `query_ids` (the
  /// finer level's own index): an object whose rows are all searched is then answered a leaf of
  /// its queries at a time (knn_same_object over both indices), the same lists.
  NeighborList same_object_list(int slot, const Points& query,
                                const std::vector<int32_t>& query_ids,
                                const std::vector<int32_t>& query_origin,
                                const Points& source_points, const ObjectIndex& sources,
                                const std::vector<int32_t>& source_origin, int k,
                                const ObjectIndex* queries = nullptr);

 private:
  // One object's anchor for one list: its query and source points (by origin and position) when
  // the list was searched and, per query row, the min(k+1, sources) nearest (local source indices),
  // the distance of the last of them and the smallest gap between consecutive distances.
  struct Entry {
    Entry(int32_t id_, int k_, std::vector<int32_t> queries, std::vector<int32_t> sources,
          Points points)
        : id(id_),
          k(k_),
          query_origin(std::move(queries)),
          source_origin(std::move(sources)),
          anchor(std::move(points)) {}
    int32_t id = 0;
    int k = 0;
    std::vector<int32_t> query_origin;
    std::vector<int32_t> source_origin;
    Points anchor = Points(0, 3);  // query points, then source points
    bool anchored = false;         // false: only the points are kept (seen once so far)
    int width = 0;
    std::vector<int32_t> nearest;  // [queries, width], sorted
    std::vector<double> farthest;  // [queries]
    std::vector<double> gap;       // [queries]
  };

  std::vector<std::vector<Entry>> slots_;
  int64_t reused_rows_ = 0;
  int64_t searched_rows_ = 0;
};

}  // namespace dynscope
