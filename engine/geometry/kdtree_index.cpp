// KdIndex: a nanoflann kd-tree in double with exact, index-ordered result sets.
#include "engine/geometry/kdtree_index.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <nanoflann.hpp>
#include <string>

#include "engine/core/error.h"
#include "engine/geometry/small_set_knn.h"

namespace dynscope {
namespace {

// Squared distances of coordinates up to this size stay far below the double range.
constexpr double kMaxCoordinate = 1e18;
// The tree's pruning bounds are sums of a few rounded squares updated once per tree level, so
// they are off by at most ~1e-14 relative; widening the bound by 1e-9 can only visit more cells.
constexpr double kBoundSlack = 1e-9;
// Points per leaf: of 6, 12 and 24, 24 was fastest for K = 16 on object surfaces in
// geometry_bench. Sets of up to kSmallSetSize points have no tree (small_set_knn answers them).
constexpr size_t kLeafSize = 24;
// knn_self keeps a leaf's candidates in a 32-bit mask.
static_assert(kLeafSize <= 32);
// knn_self ranks a first leaf with rank_nearest.
static_assert(kLeafSize <= kSmallSetSize);

// True when (sq_dist, index) orders before `b`: nearer, or as near with a lower index.
bool neighbor_before(double sq_dist, int32_t index, const Neighbor& b) {
  return sq_dist < b.sq_dist || (sq_dist == b.sq_dist && index < b.index);
}

bool neighbor_less(const Neighbor& a, const Neighbor& b) {
  return neighbor_before(a.sq_dist, a.index, b);
}

// Keeps the k smallest (squared distance, index) pairs offered to it, sorted, in a caller's
// buffer of at least k entries.
class NearestSet {
 public:
  // `count` entries of `buffer` already hold the set's first members, sorted.
  NearestSet(Neighbor* buffer, size_t k, size_t count = 0)
      : buffer_(buffer), k_(k), count_(count) {}

  size_t size() const { return count_; }
  bool full() const { return count_ == k_; }
  // The k-th squared distance once full.
  double kth() const { return buffer_[k_ - 1].sq_dist; }

  // Offers one candidate; returns true when it was kept.
  bool add(double sq_dist, int32_t index) {
    if (count_ == k_ && !neighbor_before(sq_dist, index, buffer_[k_ - 1])) return false;
    size_t j = count_ < k_ ? count_++ : k_ - 1;
    for (; j > 0 && neighbor_before(sq_dist, index, buffer_[j - 1]); --j) {
      buffer_[j] = buffer_[j - 1];
    }
    buffer_[j] = {sq_dist, index};
    return true;
  }

 private:
  Neighbor* buffer_;
  size_t k_;
  size_t count_ = 0;
};

// A bound strictly above `sq_dist` (also for 0) and above any rounding error of the tree's
// cell distances, so candidates at exactly `sq_dist` (ties) are still offered to the result set.
double widen(double sq_dist) {
  return sq_dist + sq_dist * kBoundSlack + std::numeric_limits<double>::denorm_min();
}

// Every point within `max_sq_dist` of `query`, the min(k, count) nearest kept, sorted: the
// answer when neither the tree nor small_set_knn can (queries whose squared distances could
// overflow, radius queries of sets without a tree).
void scan(const Points& points, const Vec3& query, size_t k, double max_sq_dist,
          std::vector<Neighbor>& out) {
  out.clear();
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    const double d = squared_distance(query, points.row(i).transpose());
    if (d <= max_sq_dist) out.push_back({d, static_cast<int32_t>(i)});
  }
  const size_t keep = std::min(k, out.size());
  std::partial_sort(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(keep), out.end(),
                    [](const Neighbor& a, const Neighbor& b) { return neighbor_less(a, b); });
  out.resize(keep);
}

// nanoflann's result-set interface over a NearestSet, limited to squared distance <= sq_limit.
class KnnResult {
 public:
  KnnResult(const int32_t* original, Neighbor* buffer, size_t k, double sq_limit)
      : original_(original), set_(buffer, k), sq_limit_(sq_limit), bound_(widen(sq_limit)) {}

  size_t size() const { return set_.size(); }
  bool full() const { return set_.full(); }
  double worstDist() const { return bound_; }

  bool addPoint(double sq_dist, uint32_t slot) {
    if (sq_dist <= sq_limit_ && set_.add(sq_dist, original_[slot]) && set_.full()) {
      bound_ = widen(set_.kth());
    }
    return true;
  }

 private:
  const int32_t* original_;
  NearestSet set_;
  double sq_limit_;
  double bound_;
};

// Every candidate with squared distance <= a limit, unsorted.
class RadiusResult {
 public:
  RadiusResult(const int32_t* original, std::vector<Neighbor>& out, double sq_limit)
      : original_(original), out_(out), sq_limit_(sq_limit), bound_(widen(sq_limit)) {}

  size_t size() const { return out_.size(); }
  bool full() const { return true; }
  double worstDist() const { return bound_; }

  bool addPoint(double sq_dist, uint32_t slot) {
    if (sq_dist <= sq_limit_) out_.push_back({sq_dist, original_[slot]});
    return true;
  }

 private:
  const int32_t* original_;
  std::vector<Neighbor>& out_;
  double sq_limit_;
  double bound_;
};

}  // namespace

struct KdIndex::Tree {
  // nanoflann's view of `xyz`: point i is xyz[3i .. 3i+2].
  struct Source {
    const Tree* tree;
    size_t kdtree_get_point_count() const { return tree->original.size(); }
    double kdtree_get_pt(uint32_t i, size_t dim) const { return tree->xyz[3 * i + dim]; }
    template <class Box>
    bool kdtree_get_bbox(Box&) const {
      return false;
    }
  };

  // squared_distance() itself, so tree distances round exactly as every other caller's.
  struct Metric {
    using ElementType = double;
    using DistanceType = double;
    explicit Metric(const Source& s) : source(s) {}
    double evalMetric(const double* a, uint32_t i, size_t) const {
      const double* p = &source.tree->xyz[3 * i];
      return squared_distance(Vec3(a[0], a[1], a[2]), Vec3(p[0], p[1], p[2]));
    }
    template <typename U, typename V>
    double accum_dist(U a, V b, size_t) const {
      return (a - b) * (a - b);
    }
    const Source& source;
  };

  using Index = nanoflann::KDTreeSingleIndexAdaptor<Metric, Source, 3, uint32_t>;

  explicit Tree(const Points& points)
      : xyz(points.data(), points.data() + points.size()),
        original(static_cast<size_t>(points.rows())),
        source{this},
        index(3, source, nanoflann::KDTreeSingleIndexAdaptorParams(kLeafSize)) {
    // Store the points in leaf order so that a leaf's points are contiguous in memory: the tree
    // addresses points through vAcc, which becomes the identity over the permuted storage.
    std::vector<double> sorted(xyz.size());
    for (size_t slot = 0; slot < index.vAcc.size(); ++slot) {
      const uint32_t i = index.vAcc[slot];
      original[slot] = static_cast<int32_t>(i);
      std::copy_n(&xyz[3 * i], 3, &sorted[3 * slot]);
      index.vAcc[slot] = static_cast<uint32_t>(slot);
    }
    xyz.swap(sorted);
    cells.reserve(2 * original.size() / kLeafSize + 2);
    flatten(index.root_node);
  }

  // A node of the tree with the tight box of its points (storage slots begin .. end - 1).
  struct Cell {
    std::array<double, 3> lo, hi;
    std::array<int32_t, 2> child;  // {-1, -1} for a leaf
    uint32_t begin, end;
  };

  // Squared distance between two boxes. Rounding is monotone and the summation order is
  // squared_distance()'s, so it is never above the computed distance of a point of one box to a
  // point of the other: pruning with it cannot lose a neighbour.
  static double box_distance(const Cell& a, const Cell& b) {
    double s = 0.0;
    for (int d = 0; d < 3; ++d) {
      const double gap = std::max(0.0, std::max(a.lo[d] - b.hi[d], b.lo[d] - a.hi[d]));
      s += gap * gap;
    }
    return s;
  }

  // The same for one point and a box.
  static double point_box_distance(const double* p, const Cell& b) {
    double s = 0.0;
    for (int d = 0; d < 3; ++d) {
      const double gap = std::max(0.0, std::max(b.lo[d] - p[d], p[d] - b.hi[d]));
      s += gap * gap;
    }
    return s;
  }

  // Copies the subtree of `node` into `cells` (children after their parent) and returns its cell.
  int32_t flatten(const Index::Node* node) {
    const auto id = static_cast<int32_t>(cells.size());
    cells.emplace_back();
    if (node->child1 == nullptr && node->child2 == nullptr) {
      Cell c{};
      c.child = {-1, -1};
      c.begin = static_cast<uint32_t>(node->node_type.lr.left);
      c.end = static_cast<uint32_t>(node->node_type.lr.right);
      c.lo.fill(std::numeric_limits<double>::infinity());
      c.hi.fill(-std::numeric_limits<double>::infinity());
      for (uint32_t slot = c.begin; slot < c.end; ++slot) {
        for (int d = 0; d < 3; ++d) {
          c.lo[d] = std::min(c.lo[d], xyz[3 * slot + d]);
          c.hi[d] = std::max(c.hi[d], xyz[3 * slot + d]);
        }
      }
      cells[static_cast<size_t>(id)] = c;
      leaves.push_back(id);
      return id;
    }
    const int32_t a = flatten(node->child1);
    const int32_t b = flatten(node->child2);
    const Cell& ca = cells[static_cast<size_t>(a)];
    const Cell& cb = cells[static_cast<size_t>(b)];
    Cell c{};
    c.child = {a, b};
    c.begin = std::min(ca.begin, cb.begin);
    c.end = std::max(ca.end, cb.end);
    for (int d = 0; d < 3; ++d) {
      c.lo[d] = std::min(ca.lo[d], cb.lo[d]);
      c.hi[d] = std::max(ca.hi[d], cb.hi[d]);
    }
    cells[static_cast<size_t>(id)] = c;
    return id;
  }

  std::vector<double> xyz;
  std::vector<int32_t> original;  // input index of the point in each storage slot
  Source source;
  Index index;
  std::vector<Cell> cells;      // cells[0] is the root
  std::vector<int32_t> leaves;  // the leaf cells
};

KdIndex::KdIndex(const Points& points, const char* what) : points_(points) {
  for (Eigen::Index i = 0; i < points_.rows(); ++i) {
    if (!points_.row(i).allFinite() || points_.row(i).cwiseAbs().maxCoeff() > kMaxCoordinate) {
      throw ValueError(what, "point " + std::to_string(i) + " is not finite or exceeds 1e18");
    }
  }
  if (points_.rows() > static_cast<Eigen::Index>(kSmallSetSize)) {
    tree_ = std::make_unique<Tree>(points_);
  }
}

KdIndex::~KdIndex() = default;
KdIndex::KdIndex(KdIndex&&) noexcept = default;
KdIndex& KdIndex::operator=(KdIndex&&) noexcept = default;

void KdIndex::knn(const Vec3& query, int k, std::vector<Neighbor>& out, double max_sq_dist) const {
  out.clear();
  if (!query.allFinite()) throw ValueError("query", "point is not finite");
  if (points_.rows() == 0 || k <= 0 || !(max_sq_dist >= 0.0)) return;
  const auto wanted = std::min(static_cast<size_t>(k), static_cast<size_t>(points_.rows()));
  if (query.cwiseAbs().maxCoeff() > kMaxCoordinate) {
    scan(points_, query, wanted, max_sq_dist, out);
    return;
  }
  out.resize(wanted);
  if (!tree_) {
    out.resize(small_set_knn(points_.data(), static_cast<size_t>(points_.rows()), query, wanted,
                             max_sq_dist, out.data()));
    return;
  }
  KnnResult result(tree_->original.data(), out.data(), wanted, max_sq_dist);
  tree_->index.findNeighbors(result, query.data(), nanoflann::SearchParams());
  out.resize(result.size());
}

void KdIndex::radius(const Vec3& query, double radius, std::vector<Neighbor>& out) const {
  out.clear();
  if (!query.allFinite()) throw ValueError("query", "point is not finite");
  if (points_.rows() == 0 || !(radius >= 0.0)) return;
  const double sq_limit = radius * radius;
  if (!tree_ || query.cwiseAbs().maxCoeff() > kMaxCoordinate) {
    scan(points_, query, static_cast<size_t>(points_.rows()), sq_limit, out);
    return;
  }
  RadiusResult result(tree_->original.data(), out, sq_limit);
  tree_->index.findNeighbors(result, query.data(), nanoflann::SearchParams());
  std::sort(out.begin(), out.end(),
            [](const Neighbor& a, const Neighbor& b) { return neighbor_less(a, b); });
}

size_t KdIndex::self_groups() const {
  if (tree_) return tree_->leaves.size();
  return points_.rows() > 0 ? 1 : 0;
}

void KdIndex::knn_self(size_t group, int k, std::vector<Neighbor>& scratch,
                       const SelfAnswer& answer) const {
  if (k <= 0 || group >= self_groups()) return;
  const auto wanted = std::min(static_cast<size_t>(k), static_cast<size_t>(points_.rows()));
  if (!tree_) {
    for (Eigen::Index i = 0; i < points_.rows(); ++i) {
      knn(point(i), k, scratch);
      answer(i, scratch.data(), scratch.size());
    }
    return;
  }
  using Cell = Tree::Cell;
  const Tree& t = *tree_;
  const Cell& own = t.cells[static_cast<size_t>(t.leaves[group])];
  const uint32_t queries = own.end - own.begin;
  scratch.resize(static_cast<size_t>(queries) * wanted);
  std::array<size_t, kLeafSize> count{};
  // Offers every point of `leaf` to every query of the group whose k-th distance can reach it.
  auto visit = [&](const Cell& leaf) {
    std::array<double, kLeafSize> d{};
    const uint32_t n = leaf.end - leaf.begin;
    for (uint32_t qi = 0; qi < queries; ++qi) {
      const double* q = &t.xyz[3 * (own.begin + qi)];
      Neighbor* best = &scratch[qi * wanted];
      size_t c = count[qi];
      const bool full = c == wanted;
      if (full && Tree::point_box_distance(q, leaf) > widen(best[wanted - 1].sq_dist)) continue;
      for (uint32_t j = 0; j < n; ++j) {
        const double* p = &t.xyz[3 * (leaf.begin + j)];
        const double dx = q[0] - p[0], dy = q[1] - p[1], dz = q[2] - p[2];
        d[j] = dx * dx + dy * dy + dz * dz;  // squared_distance()'s rounding
      }
      if (c == 0) {
        // The first leaf (the group's own): every candidate placed by counting, not inserted.
        count[qi] = rank_nearest(d.data(), &t.original[leaf.begin], n, wanted,
                                 std::numeric_limits<double>::infinity(), best);
        continue;
      }
      // Candidates at or below the k-th distance as a bit mask, computed without branches; only
      // those are inserted, in index order within the leaf.
      const double limit =
          full ? best[wanted - 1].sq_dist : std::numeric_limits<double>::infinity();
      uint32_t mask = 0;
      for (uint32_t j = 0; j < n; ++j) mask |= static_cast<uint32_t>(d[j] <= limit) << j;
      NearestSet set(best, wanted, c);
      while (mask != 0) {
        const auto j = static_cast<uint32_t>(__builtin_ctz(mask));
        mask &= mask - 1;
        set.add(d[j], t.original[leaf.begin + j]);
      }
      count[qi] = set.size();
    }
  };
  // The largest k-th distance of the group's queries (infinite while one has fewer than k).
  auto group_bound = [&]() {
    double bound = 0.0;
    for (uint32_t qi = 0; qi < queries; ++qi) {
      if (count[qi] < wanted) return std::numeric_limits<double>::infinity();
      bound = std::max(bound, scratch[qi * wanted + wanted - 1].sq_dist);
    }
    return bound;
  };
  visit(own);
  double bound = group_bound();
  std::vector<int32_t> stack{0};
  while (!stack.empty()) {
    const Cell& cell = t.cells[static_cast<size_t>(stack.back())];
    stack.pop_back();
    if (&cell == &own || Tree::box_distance(own, cell) > widen(bound)) continue;
    if (cell.child[0] < 0) {
      visit(cell);
      bound = group_bound();
      continue;
    }
    // The nearer child is visited first (pushed last).
    const int32_t a = cell.child[0], b = cell.child[1];
    const bool a_first = Tree::box_distance(own, t.cells[static_cast<size_t>(a)]) <=
                         Tree::box_distance(own, t.cells[static_cast<size_t>(b)]);
    stack.push_back(a_first ? b : a);
    stack.push_back(a_first ? a : b);
  }
  for (uint32_t qi = 0; qi < queries; ++qi) {
    answer(t.original[own.begin + qi], &scratch[qi * wanted], count[qi]);
  }
}

}  // namespace dynscope
