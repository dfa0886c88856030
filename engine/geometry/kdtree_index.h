// Exact double-precision nearest-neighbour and radius queries over a fixed point set (PCL inside).
#pragma once

#include <cstdint>
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

/// Kd-tree over `[N,3]` points whose answers equal a brute-force search in double: PCL's float
/// tree proposes candidates with a safety margin, and distances are recomputed in double. Results
/// are sorted by (squared distance, index), so ties resolve to the lowest index.
class KdIndex {
 public:
  /// Copies `points` (may have zero rows). Throws ValueError(`what`) if a coordinate is not
  /// finite or too large for the float tree (|x| > 1e18).
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
  /// Replaces `out` with the min(k, size()) nearest points to `query`, sorted; empty for k <= 0.
  void knn(const Vec3& query, int k, std::vector<Neighbor>& out) const;
  /// Replaces `out` with every point whose squared distance to `query` is <= radius², sorted.
  void radius(const Vec3& query, double radius, std::vector<Neighbor>& out) const;

 private:
  struct Tree;
  /// Upper bound on |float distance − exact distance| for a query, given a distance scale.
  double margin(const Vec3& query, double distance) const;
  /// Float-tree radius search followed by exact filtering at `exact_sq_limit`.
  void radius_candidates(const Vec3& query, double float_radius, double exact_sq_limit,
                         std::vector<Neighbor>& out) const;

  Points points_;
  Vec3 centre_ = Vec3::Zero();
  double extent_ = 0.0;
  std::unique_ptr<Tree> tree_;
};

}  // namespace dynscope
