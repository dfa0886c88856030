// Exact double-precision nearest-neighbour and radius queries over a fixed point set.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <vector>

#include "engine/core/types.h"

namespace dynscope {

/// One neighbour of a query: squared Euclidean distance (double) and index into the indexed set.
struct Neighbor {
  double sq_dist = 0.0;
  int32_t index = -1;
};

/// Squared Euclidean distance in double, written once so that every caller rounds identically.
inline double squared_distance(const Vec3& a, const Vec3& b) {
  const double dx = a.x() - b.x(), dy = a.y() - b.y(), dz = a.z() - b.z();
  return dx * dx + dy * dy + dz * dz;
}

/// The gap between the intervals [a_lo, a_hi] and [b_lo, b_hi] on one axis (0 where they meet):
/// never above |a − b| as rounded for any a and b in them (subtraction rounds monotonically).
inline double axis_gap(double a_lo, double a_hi, double b_lo, double b_hi) {
  return std::max(0.0, std::max(a_lo - b_hi, b_lo - a_hi));
}

/// Squared distance between two axis-aligned boxes given by their corners (three coordinates
/// each; a point is the box with both corners at it), summed in squared_distance()'s order.
/// Rounding is monotone, so it is never above the computed squared_distance() of a point of one
/// box to a point of the other: pruning with it cannot lose a neighbour.
inline double squared_box_distance(const double* a_lo, const double* a_hi, const double* b_lo,
                                   const double* b_hi) {
  double s = 0.0;
  for (int d = 0; d < 3; ++d) {
    const double gap = axis_gap(a_lo[d], a_hi[d], b_lo[d], b_hi[d]);
    s += gap * gap;
  }
  return s;
}

/// Kd-tree over `[N,3]` points whose answers equal a brute-force search in double: distances are
/// squared_distance()'s, and a cell is skipped only when a bound that never exceeds any of its
/// points' computed distances is beyond the answer's, so no candidate at or below the answer's
/// distance is ever skipped. Cells split the middle of their tight box's widest axis (the median
/// when that leaves under a quarter on one side); trees of 16k points and more are built on the
/// compute threads, into the same tree for every thread count. Results are sorted by (squared
/// distance, index), so ties resolve to the lowest index. Const queries may run concurrently
/// from several threads.
class KdIndex {
 public:
  /// Copies `points` (may have zero rows). Throws ValueError(`what`) if a coordinate is not
  /// finite or too large for squared distances to stay finite (|x| > 1e18).
  explicit KdIndex(const Points& points, const char* what = "points");
  ~KdIndex();
  KdIndex(KdIndex&&) noexcept;
  KdIndex& operator=(KdIndex&&) noexcept;
  KdIndex(const KdIndex&) = delete;
  KdIndex& operator=(const KdIndex&) = delete;

  /// Number of indexed points.
  Eigen::Index size() const { return points_.rows(); }
  /// Indexed point `i`.
  Vec3 point(Eigen::Index i) const { return points_.row(i).transpose(); }
  /// Replaces `out` with the min(k, size()) nearest points to `query` whose squared distance is
  /// <= `max_sq_dist` (default: no limit), sorted; empty for k <= 0. Throws ValueError for a
  /// non-finite query.
  void knn(const Vec3& query, int k, std::vector<Neighbor>& out,
           double max_sq_dist = std::numeric_limits<double>::infinity()) const;
  /// Queries knn_rows() answers together on a set too small for a tree: callers that group their
  /// queries by index do best with runs of this many.
  static constexpr size_t kBatchRows = 8;

  /// knn() without a distance limit for `m` queries (`queries` row-major x, y, z): writes query
  /// i's min(k, size()) nearest to out[i·min(k, size()) ...] and returns min(k, size()) (0 for
  /// k <= 0 or an empty set). Sets too small for a tree answer several queries together
  /// (small_set_knn_batch), much faster than one knn() each. Throws ValueError for a non-finite
  /// query.
  size_t knn_rows(const double* queries, size_t m, int k, Neighbor* out) const;

  /// Replaces `out` with every point whose squared distance to `query` is <= radius², sorted
  /// (nearest first, ties by index) unless `sorted` is false, which leaves them in an unspecified
  /// order for callers that order them their own way. Throws ValueError for a non-finite query.
  void radius(const Vec3& query, double radius, std::vector<Neighbor>& out,
              bool sorted = true) const;

  /// Receives one indexed point's answer from knn_self: its index and its sorted neighbours.
  using SelfAnswer = std::function<void(Eigen::Index point, const Neighbor* nearest, size_t count)>;
  /// Number of groups of indexed points that knn_self answers together (the tree's leaves; one
  /// for a set too small for a tree, none for an empty one).
  size_t self_groups() const;
  /// The indexed points' own k nearest (each point included), for every point of group `group`:
  /// calls answer(i, nearest, count) with what knn(point(i), k) returns, once per point of the
  /// group. Faster than one knn() per point: the tree is walked once per group against the
  /// group's box, each point skips the leaves its own k-th distance cannot reach, and a leaf's
  /// distances are computed together and only those within the k-th distance are inserted.
  /// `scratch` is the caller's buffer (one per thread); groups may run concurrently. Nothing is
  /// called for k <= 0 or a group out of range.
  void knn_self(size_t group, int k, std::vector<Neighbor>& scratch,
                const SelfAnswer& answer) const;

  /// For every point of group `group` (as knn_self's groups), what other.knn(point(i), k) returns:
  /// its k nearest points of `other` (another set, e.g. the same object's points at a coarser
  /// level). Calls answer(i, nearest, count) once per point of the group. Faster than one knn() per
  /// point when the group's points are near `other`'s: `other`'s tree is walked once per group
  /// against the group's box and the largest k-th distance of its points, and each point skips the
  /// leaves its own k-th distance cannot reach. `scratch` is the caller's buffer (one per thread);
  /// groups may run concurrently. Nothing is called for k <= 0 or a group out of range.
  void knn_other(size_t group, const KdIndex& other, int k, std::vector<Neighbor>& scratch,
                 const SelfAnswer& answer) const;

 private:
  struct Tree;

  Points points_;
  std::unique_ptr<Tree> tree_;
};

}  // namespace dynscope
