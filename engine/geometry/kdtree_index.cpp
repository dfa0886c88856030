// KdIndex: a kd-tree in double with tight cell boxes and exact, index-ordered result sets.
#include "engine/geometry/kdtree_index.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <exception>
#include <string>

#include "engine/core/error.h"
#include "engine/core/parallel.h"
#include "engine/geometry/small_set_knn.h"

namespace dynscope {
namespace {

// Squared distances of coordinates up to this size stay far below the double range.
constexpr double kMaxCoordinate = 1e18;
// Pruning compares bounds that never exceed a computed point distance; widening the k-th distance
// by 1e-9 relative on top can only visit more cells, and keeps ties at the k-th distance offered.
constexpr double kBoundSlack = 1e-9;
// Points per leaf: of 6, 12 and 24, 24 was fastest for K = 16 on object surfaces in
// geometry_bench. Sets of up to kSmallSetSize points have no tree (small_set_knn answers them).
constexpr size_t kLeafSize = 24;
// knn_self keeps a leaf's candidates in a 32-bit mask.
static_assert(kLeafSize <= 32);
// knn_self ranks a first leaf with rank_nearest.
static_assert(kLeafSize <= kSmallSetSize);
// Trees of at least this many points build their top kParallelBuildLevels levels first and the
// 2^kParallelBuildLevels subtrees below them on the compute threads.
constexpr uint32_t kParallelBuildPoints = 16384;
constexpr int kParallelBuildLevels = 2;

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

// A bound strictly above `sq_dist` (also for 0), so candidates at exactly `sq_dist` (ties) are
// still offered to the result set.
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

// The k nearest offered points with squared distance <= sq_limit, for Tree::descend.
class KnnResult {
 public:
  KnnResult(const int32_t* original, Neighbor* buffer, size_t k, double sq_limit)
      : original_(original), set_(buffer, k), sq_limit_(sq_limit), bound_(widen(sq_limit)) {}

  size_t size() const { return set_.size(); }
  // A subtree whose distance bound exceeds this has nothing to offer.
  double bound() const { return bound_; }

  void add(double sq_dist, uint32_t slot) {
    if (sq_dist <= sq_limit_ && set_.add(sq_dist, original_[slot]) && set_.full()) {
      bound_ = widen(set_.kth());
    }
  }

 private:
  const int32_t* original_;
  NearestSet set_;
  double sq_limit_;
  double bound_;
};

// Every offered point with squared distance <= sq_limit, unsorted.
class RadiusResult {
 public:
  RadiusResult(const int32_t* original, std::vector<Neighbor>& out, double sq_limit)
      : original_(original), out_(out), sq_limit_(sq_limit), bound_(widen(sq_limit)) {}

  double bound() const { return bound_; }

  void add(double sq_dist, uint32_t slot) {
    if (sq_dist <= sq_limit_) out_.push_back({sq_dist, original_[slot]});
  }

 private:
  const int32_t* original_;
  std::vector<Neighbor>& out_;
  double sq_limit_;
  double bound_;
};

// A point during the build: coordinates and input index together, so splitting a cell moves one
// contiguous record.
struct Slot {
  std::array<double, 3> p;
  int32_t original;
};

}  // namespace

struct KdIndex::Tree {
  // A node of the tree with the tight box of its points (storage slots begin .. end - 1). An inner
  // node's children split its points along axis `axis`: every coordinate of the first is at or
  // below every coordinate of the second on that axis.
  struct Cell {
    std::array<double, 3> lo, hi;
    std::array<int32_t, 2> child;  // {-1, -1} for a leaf
    uint32_t begin, end;
    int32_t axis;
  };

  explicit Tree(const Points& points) {
    const auto n = static_cast<uint32_t>(points.rows());
    xyz.resize(3 * static_cast<size_t>(n));
    original.resize(n);
    Buffers buffers{std::vector<Slot>(n), std::vector<Slot>(n)};
    for (uint32_t i = 0; i < n; ++i) {
      buffers.slots[0][i] = {{points(i, 0), points(i, 1), points(i, 2)}, static_cast<int32_t>(i)};
    }
    cells.reserve(2 * static_cast<size_t>(n) / (kLeafSize / 2) + 2);
    // The top levels are split here; below them the parts are built on the compute threads, each
    // into its own list, and spliced in. The parts are the same for every thread count, and so is
    // the tree (only the order of the cells in memory differs from a serial build).
    const int levels = n >= kParallelBuildPoints ? kParallelBuildLevels : 0;
    std::vector<Part> parts;
    build(buffers, 0, 0, n, cells, levels, &parts);
    std::vector<std::vector<Cell>> built(parts.size());
    std::vector<std::exception_ptr> failed(parts.size());  // rethrown after the loop
    parallel_chunks(static_cast<int64_t>(parts.size()), 1, true, [&](int64_t i, int64_t) {
      try {
        const Part& part = parts[static_cast<size_t>(i)];
        std::vector<Cell>& cells_of_part = built[static_cast<size_t>(i)];
        cells_of_part.reserve(2 * static_cast<size_t>(part.end - part.begin) / (kLeafSize / 2) + 2);
        build(buffers, part.from, part.begin, part.end, cells_of_part);
      } catch (...) {
        failed[static_cast<size_t>(i)] = std::current_exception();
      }
    });
    for (const std::exception_ptr& e : failed) {
      if (e) std::rethrow_exception(e);
    }
    for (size_t i = 0; i < parts.size(); ++i) splice(parts[i].cell, built[i]);
    collect_leaves(0);
    nodes.resize(cells.size());
    for (size_t i = 0; i < cells.size(); ++i) {
      const Cell& c = cells[i];
      if (c.child[0] < 0) {
        nodes[i] = {0.0, 0.0, static_cast<int32_t>(c.begin), static_cast<int32_t>(c.end), -1};
      } else {
        const auto axis = static_cast<size_t>(c.axis);
        nodes[i] = {cells[static_cast<size_t>(c.child[0])].hi[axis],
                    cells[static_cast<size_t>(c.child[1])].lo[axis], c.child[0], c.child[1],
                    c.axis};
      }
    }
  }

  // Squared distance between two cells, and between a point and a cell (squared_box_distance).
  static double box_distance(const Cell& a, const Cell& b) {
    return squared_box_distance(a.lo.data(), a.hi.data(), b.lo.data(), b.hi.data());
  }
  static double point_box_distance(const double* p, const Cell& b) {
    return squared_box_distance(p, p, b.lo.data(), b.hi.data());
  }

  // What a search descends through: one cell in 32 bytes, the two planes of its split (the
  // largest coordinate of the first child and the smallest of the second on the split axis) or,
  // for a leaf, its slots.
  struct Node {
    double below, above;  // split planes (inner node)
    int32_t a, b;         // children (inner node) or slots a .. b - 1 (leaf)
    int32_t axis;         // split axis, -1 for a leaf
  };

  // Offers `result` every point of the tree within its bound of `q`. `gap2[d]` is the squared
  // distance along axis d from q to an interval holding every point of the node, so their sum (in
  // squared_distance()'s order, rounding monotonically) is never above a point's computed
  // distance: a subtree is skipped only when none of its points can be offered. The child on
  // the query's side of the split is searched first with the parent's bound (valid for it too),
  // the other with its gap to the split plane on the split axis, if still in reach.
  template <class Result>
  void descend(int32_t id, const double* q, std::array<double, 3>& gap2, Result& result) const {
    const Node& node = nodes[static_cast<size_t>(id)];
    if (node.axis < 0) {
      // The leaf's distances together, then only the points within the bound offered (the bound
      // may shrink as they are: the result checks each against its own).
      std::array<double, kLeafSize> d;
      const auto first = static_cast<uint32_t>(node.a);
      uint32_t mask =
          leaf_candidates(&xyz[3 * static_cast<size_t>(first)],
                          static_cast<uint32_t>(node.b) - first, q, result.bound(), d.data());
      while (mask != 0) {
        const auto j = static_cast<uint32_t>(__builtin_ctz(mask));
        mask &= mask - 1;
        result.add(d[j], first + j);
      }
      return;
    }
    const auto axis = static_cast<size_t>(node.axis);
    const double v = q[axis];
    const bool a_first = (v - node.below) + (v - node.above) < 0.0;
    descend(a_first ? node.a : node.b, q, gap2, result);
    const double far = std::max(0.0, a_first ? node.above - v : v - node.below);
    const double saved = gap2[axis];
    gap2[axis] = far * far;
    if (gap2[0] + gap2[1] + gap2[2] <= result.bound()) {
      descend(a_first ? node.b : node.a, q, gap2, result);
    }
    gap2[axis] = saved;
  }

  // Searches the whole tree for `q`.
  template <class Result>
  void search(const double* q, Result& result) const {
    std::array<double, 3> gap2{};
    for (int d = 0; d < 3; ++d) {
      const double g = axis_gap(q[d], q[d], cells[0].lo[d], cells[0].hi[d]);
      gap2[static_cast<size_t>(d)] = g * g;
    }
    if (gap2[0] + gap2[1] + gap2[2] <= result.bound()) descend(0, q, gap2, result);
  }

  // Offers this tree's points to `queries` points (`q`, row-major x, y, z) lying in the box lo ..
  // hi, keeping each point's `wanted` nearest, sorted, in best[qi·wanted ...] (count[qi] of them,
  // which must start at 0; `queries` <= kSmallSetSize). The tree is walked once against the box and
  // the largest k-th distance of the points (a cell is skipped only when no point can reach it, by
  // monotone rounding as in descend); each point skips the leaves its own k-th distance cannot
  // reach, computes a leaf's distances together and inserts only those within it, and ranks its
  // first leaf by counting. `first`, when given, is visited before the walk and skipped in it.
  void search_group(const double* q, uint32_t queries, const std::array<double, 3>& lo,
                    const std::array<double, 3>& hi, size_t wanted, Neighbor* best, size_t* count,
                    const Cell* first) const {
    auto full = [&](uint32_t qi) { return count[qi] == wanted; };
    auto kth = [&](uint32_t qi) { return best[qi * wanted + wanted - 1].sq_dist; };
    // Offers every point of `leaf` to every point of the group whose k-th distance can reach it.
    auto visit = [&](const Cell& leaf) {
      std::array<double, kLeafSize> d{};
      const uint32_t n = leaf.end - leaf.begin;
      for (uint32_t qi = 0; qi < queries; ++qi) {
        const double* p = &q[3 * qi];
        if (full(qi) && point_box_distance(p, leaf) > widen(kth(qi))) continue;
        // The leaf's distances, and its candidates at or below the k-th distance as a bit mask.
        const double limit = full(qi) ? kth(qi) : std::numeric_limits<double>::infinity();
        uint32_t mask = leaf_candidates(&xyz[3 * leaf.begin], n, p, limit, d.data());
        Neighbor* own = &best[qi * wanted];
        if (count[qi] == 0) {
          // The first leaf: every candidate placed by counting, not inserted.
          count[qi] = rank_nearest(d.data(), &original[leaf.begin], n, wanted,
                                   std::numeric_limits<double>::infinity(), own);
          continue;
        }
        // Only the candidates are inserted, in index order within the leaf.
        NearestSet set(own, wanted, count[qi]);
        while (mask != 0) {
          const auto j = static_cast<uint32_t>(__builtin_ctz(mask));
          mask &= mask - 1;
          set.add(d[j], original[leaf.begin + j]);
        }
        count[qi] = set.size();
      }
    };
    // The largest k-th distance of the group's points (infinite while one has fewer than k).
    auto group_bound = [&]() {
      double bound = 0.0;
      for (uint32_t qi = 0; qi < queries; ++qi) {
        if (!full(qi)) return std::numeric_limits<double>::infinity();
        bound = std::max(bound, kth(qi));
      }
      return bound;
    };
    auto distance_to = [&](const Cell& c) {
      return squared_box_distance(lo.data(), hi.data(), c.lo.data(), c.hi.data());
    };
    if (first != nullptr) visit(*first);
    double bound = group_bound();
    std::vector<int32_t> stack{0};
    while (!stack.empty()) {
      const Cell& cell = cells[static_cast<size_t>(stack.back())];
      stack.pop_back();
      if (&cell == first || distance_to(cell) > widen(bound)) continue;
      if (cell.child[0] < 0) {
        visit(cell);
        bound = group_bound();
        continue;
      }
      // The nearer child is visited first (pushed last).
      const int32_t a = cell.child[0], b = cell.child[1];
      const bool a_first =
          distance_to(cells[static_cast<size_t>(a)]) <= distance_to(cells[static_cast<size_t>(b)]);
      stack.push_back(a_first ? b : a);
      stack.push_back(a_first ? a : b);
    }
  }

  std::vector<double> xyz;        // the points in leaf order (x, y, z per storage slot)
  std::vector<int32_t> original;  // input index of the point in each storage slot
  std::vector<Cell> cells;        // cells[0] is the root
  std::vector<Node> nodes;        // the cells as the searches read them (same indices)
  std::vector<int32_t> leaves;    // the leaf cells, in storage order

 private:
  // The points during the build, in two buffers: a node reads its slots from one and writes them
  // split into the other, where its children read them.
  struct Buffers {
    std::array<std::vector<Slot>, 2> slots;
  };

  // Below the top levels: a part of the points built into a list of its own.
  struct Part {
    int32_t cell;  // the cell the part's root replaces
    int from;      // the buffer holding the part's points
    uint32_t begin, end;
  };

  // The tight box of slots begin .. end - 1 (at least one).
  static Cell bounds(const Slot* slots, uint32_t begin, uint32_t end) {
    // Six independent running extrema in registers.
    double lx = slots[begin].p[0], ly = slots[begin].p[1], lz = slots[begin].p[2];
    double hx = lx, hy = ly, hz = lz;
    for (uint32_t i = begin + 1; i < end; ++i) {
      const std::array<double, 3>& p = slots[i].p;
      lx = std::min(lx, p[0]);
      ly = std::min(ly, p[1]);
      lz = std::min(lz, p[2]);
      hx = std::max(hx, p[0]);
      hy = std::max(hy, p[1]);
      hz = std::max(hz, p[2]);
    }
    Cell c{};
    c.lo = {lx, ly, lz};
    c.hi = {hx, hy, hz};
    c.begin = begin;
    c.end = end;
    c.child = {-1, -1};
    c.axis = 0;
    return c;
  }

  // Copies the slots of `c` from `from` into `to` split across the middle of its box's widest
  // axis (points on the plane go first), without branches; a split leaving under a quarter on
  // one side is replaced by the median, so the depth stays logarithmic for any input. Sets c.axis
  // and returns the first slot of the second half.
  static uint32_t split(const Slot* from, Slot* to, Cell& c) {
    int axis = 0;
    for (int d = 1; d < 3; ++d) {
      if (c.hi[d] - c.lo[d] > c.hi[axis] - c.lo[axis]) axis = d;
    }
    c.axis = axis;
    const double cut = 0.5 * c.lo[axis] + 0.5 * c.hi[axis];
    // Each slot is written at both ends of the gap; only the end its side grows keeps it.
    int64_t first = c.begin, last = static_cast<int64_t>(c.end) - 1;
    for (uint32_t i = c.begin; i < c.end; ++i) {
      const Slot s = from[i];
      to[first] = s;
      to[last] = s;
      const bool below = s.p[axis] <= cut;
      first += below;
      last -= !below;
    }
    const uint32_t count = c.end - c.begin, half = count / 2;
    auto at = static_cast<uint32_t>(first - c.begin);
    if (at < count / 4 || at > count - count / 4) {
      Slot* part = to + c.begin;
      std::nth_element(part, part + half, part + count,
                       [&](const Slot& x, const Slot& y) { return x.p[axis] < y.p[axis]; });
      at = half;
    }
    return c.begin + at;
  }

  // Builds the subtree over slots begin .. end - 1 of buffer `from` into `out` and returns its
  // cell's index there; each leaf stores its points in the tree's storage slots. With a
  // non-negative `levels`, only that many levels are built: each subtree below them gets a
  // placeholder cell and an entry in `parts`, to be built on its own and spliced in.
  int32_t build(Buffers& buffers, int from, uint32_t begin, uint32_t end, std::vector<Cell>& out,
                int levels = -1, std::vector<Part>* parts = nullptr) {
    const auto id = static_cast<int32_t>(out.size());
    if (levels == 0) {
      out.emplace_back();
      parts->push_back({id, from, begin, end});
      return id;
    }
    Slot* slots = buffers.slots[static_cast<size_t>(from)].data();
    Cell c = bounds(slots, begin, end);
    out.push_back(c);
    if (end - begin <= kLeafSize) {
      // A leaf's points in input order (knn_self's ranking of a leaf breaks ties by position).
      std::sort(slots + begin, slots + end,
                [](const Slot& x, const Slot& y) { return x.original < y.original; });
      for (uint32_t i = begin; i < end; ++i) {
        std::copy_n(slots[i].p.data(), 3, &xyz[3 * static_cast<size_t>(i)]);
        original[i] = slots[i].original;
      }
      return id;
    }
    const uint32_t mid = split(slots, buffers.slots[static_cast<size_t>(1 - from)].data(), c);
    const int below = levels > 0 ? levels - 1 : levels;
    c.child[0] = build(buffers, 1 - from, begin, mid, out, below, parts);
    c.child[1] = build(buffers, 1 - from, mid, end, out, below, parts);
    out[static_cast<size_t>(id)] = c;
    return id;
  }

  // Moves a part built on its own into the tree: its root replaces the placeholder cell `at`,
  // its other cells are appended to `cells`, and its child indices are shifted to match.
  void splice(int32_t at, const std::vector<Cell>& part) {
    // Index j >= 1 in the part becomes base + j in `cells`.
    const auto base = static_cast<int32_t>(cells.size()) - 1;
    auto relabel = [&](Cell c) {
      for (int32_t& child : c.child) {
        if (child >= 0) child += base;
      }
      return c;
    };
    cells[static_cast<size_t>(at)] = relabel(part[0]);
    for (size_t j = 1; j < part.size(); ++j) cells.push_back(relabel(part[j]));
  }

  // Lists the leaves under `id` in storage order.
  void collect_leaves(int32_t id) {
    const Cell& c = cells[static_cast<size_t>(id)];
    if (c.child[0] < 0) {
      leaves.push_back(id);
      return;
    }
    collect_leaves(c.child[0]);
    collect_leaves(c.child[1]);
  }
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
  tree_->search(query.data(), result);
  out.resize(result.size());
}

size_t KdIndex::knn_rows(const double* queries, size_t m, int k, Neighbor* out) const {
  bool ordinary = true;  // no query so far out that only a scan answers it
  for (size_t i = 0; i < m; ++i) {
    const Vec3 query(queries[3 * i], queries[3 * i + 1], queries[3 * i + 2]);
    if (!query.allFinite()) throw ValueError("query", "point is not finite");
    ordinary = ordinary && query.cwiseAbs().maxCoeff() <= kMaxCoordinate;
  }
  if (points_.rows() == 0 || k <= 0) return 0;
  const auto n = static_cast<size_t>(points_.rows());
  const size_t wanted = std::min(static_cast<size_t>(k), n);
  if (!tree_ && ordinary) {
    for (size_t i = 0; i < m; i += kSmallSetBatch) {
      small_set_knn_batch(points_.data(), n, queries + 3 * i, std::min(kSmallSetBatch, m - i),
                          wanted, out + i * wanted);
    }
    return wanted;
  }
  std::vector<Neighbor> found;
  for (size_t i = 0; i < m; ++i) {
    knn(Vec3(queries[3 * i], queries[3 * i + 1], queries[3 * i + 2]), k, found);
    std::copy(found.begin(), found.end(), out + i * wanted);
  }
  return wanted;
}

void KdIndex::radius(const Vec3& query, double radius, std::vector<Neighbor>& out,
                     bool sorted) const {
  out.clear();
  if (!query.allFinite()) throw ValueError("query", "point is not finite");
  if (points_.rows() == 0 || !(radius >= 0.0)) return;
  const double sq_limit = radius * radius;
  if (!tree_ || query.cwiseAbs().maxCoeff() > kMaxCoordinate) {
    scan(points_, query, static_cast<size_t>(points_.rows()), sq_limit, out);
    return;
  }
  RadiusResult result(tree_->original.data(), out, sq_limit);
  tree_->search(query.data(), result);
  if (!sorted) return;
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
  const Tree& t = *tree_;
  const Tree::Cell& own = t.cells[static_cast<size_t>(t.leaves[group])];
  const uint32_t queries = own.end - own.begin;
  scratch.resize(static_cast<size_t>(queries) * wanted);
  std::array<size_t, kLeafSize> count{};
  t.search_group(&t.xyz[3 * static_cast<size_t>(own.begin)], queries, own.lo, own.hi, wanted,
                 scratch.data(), count.data(), &own);
  for (uint32_t qi = 0; qi < queries; ++qi) {
    answer(t.original[own.begin + qi], &scratch[qi * wanted], count[qi]);
  }
}

void KdIndex::knn_other(size_t group, const KdIndex& other, int k, std::vector<Neighbor>& scratch,
                        const SelfAnswer& answer) const {
  if (k <= 0 || group >= self_groups()) return;
  // The group's points (a leaf of this tree, or every point of a set without one): their
  // coordinates, their indices (none: the position is the index) and their box.
  const double* xyz = points_.data();  // row-major x, y, z
  const int32_t* original = nullptr;
  auto queries = static_cast<uint32_t>(points_.rows());
  std::array<double, 3> lo{}, hi{};
  if (tree_) {
    const Tree::Cell& own = tree_->cells[static_cast<size_t>(tree_->leaves[group])];
    xyz = &tree_->xyz[3 * static_cast<size_t>(own.begin)];
    original = &tree_->original[own.begin];
    queries = own.end - own.begin;
    lo = own.lo;
    hi = own.hi;
  } else {
    for (size_t d = 0; d < 3; ++d) {
      lo[d] = points_.col(static_cast<Eigen::Index>(d)).minCoeff();
      hi[d] = points_.col(static_cast<Eigen::Index>(d)).maxCoeff();
    }
  }
  auto index_of = [&](uint32_t qi) {
    return static_cast<Eigen::Index>(original != nullptr ? original[qi] : qi);
  };
  if (other.size() == 0) {
    for (uint32_t qi = 0; qi < queries; ++qi) answer(index_of(qi), nullptr, 0);
    return;
  }
  const auto wanted = std::min(static_cast<size_t>(k), static_cast<size_t>(other.size()));
  scratch.resize(static_cast<size_t>(queries) * wanted);
  if (!other.tree_) {
    // A set too small for a tree: each point ranks it, several at once.
    for (uint32_t qi = 0; qi < queries; qi += kSmallSetBatch) {
      const size_t m = std::min<size_t>(kSmallSetBatch, queries - qi);
      small_set_knn_batch(other.points_.data(), static_cast<size_t>(other.size()), &xyz[3 * qi], m,
                          wanted, &scratch[qi * wanted]);
    }
    for (uint32_t qi = 0; qi < queries; ++qi) {
      answer(index_of(qi), &scratch[qi * wanted], wanted);
    }
    return;
  }
  static_assert(kLeafSize <= kSmallSetSize);
  std::array<size_t, kSmallSetSize> count{};
  other.tree_->search_group(xyz, queries, lo, hi, wanted, scratch.data(), count.data(), nullptr);
  for (uint32_t qi = 0; qi < queries; ++qi) answer(index_of(qi), &scratch[qi * wanted], count[qi]);
}

}  // namespace dynscope
