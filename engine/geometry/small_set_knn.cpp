// small_set_knn: rank every distance of a small set. Compiled with -O3 (the ranking loops
// vectorise) and -ffp-contract=off (distances round as squared_distance()); see CMakeLists.txt.
#include "engine/geometry/small_set_knn.h"

#include <algorithm>
#include <array>

#include "engine/core/isa_clones.h"

namespace dynscope {

namespace {

// Writes each of the n candidates within the limit to its place among them in (distance,
// position) order, if that place is below k, and returns how many it wrote: the points ordering
// before candidate i are the nearer ones and the equally near ones ahead of it. A candidate
// beyond the limit is farther than every one within it, so it never counts. Branch-free loops
// that vectorise; inlined into each instruction-set clone of its callers.
[[gnu::always_inline]] inline size_t rank_by_position(const double* d, const int32_t* index,
                                                      size_t n, size_t k, double max_sq_dist,
                                                      Neighbor* out) {
  size_t count = 0;
  for (size_t i = 0; i < n; ++i) {
    const double di = d[i];
    if (!(di <= max_sq_dist)) continue;
    ++count;
    size_t place = 0;
    for (size_t j = 0; j < i; ++j) place += d[j] <= di ? 1 : 0;
    for (size_t j = i + 1; j < n; ++j) place += d[j] < di ? 1 : 0;
    if (place < k) out[place] = {di, index != nullptr ? index[i] : static_cast<int32_t>(i)};
  }
  return std::min(count, k);
}

}  // namespace

DYNSCOPE_ISA_CLONES
size_t small_set_knn(const double* xyz, size_t n, const Vec3& query, size_t k, double max_sq_dist,
                     Neighbor* out) {
  n = std::min(n, kSmallSetSize);
  std::array<double, kSmallSetSize> d;
  const double qx = query.x(), qy = query.y(), qz = query.z();
  for (size_t j = 0; j < n; ++j) {
    const double dx = qx - xyz[3 * j], dy = qy - xyz[3 * j + 1], dz = qz - xyz[3 * j + 2];
    d[j] = dx * dx + dy * dy + dz * dz;  // squared_distance()'s rounding
  }
  // The indices are the positions.
  return rank_by_position(d.data(), nullptr, n, k, max_sq_dist, out);
}

namespace {

// Vectors of kLanes doubles and of as many counts (an attribute's size cannot depend on a
// template argument, hence one specialisation per width).
template <size_t kLanes>
struct LaneVectors;
template <>
struct LaneVectors<8> {
  typedef double Doubles __attribute__((vector_size(64)));
  typedef int64_t Counts __attribute__((vector_size(64)));
};
template <>
struct LaneVectors<4> {
  typedef double Doubles __attribute__((vector_size(32)));
  typedef int64_t Counts __attribute__((vector_size(32)));
};

// small_set_knn_batch for up to kLanes queries, one lane each (spare lanes repeat the first
// query); inlined into each instruction-set clone of its caller.
template <size_t kLanes>
[[gnu::always_inline]] inline void knn_lanes(const double* xyz, size_t n, const double* queries,
                                             size_t m, size_t k, Neighbor* out) {
  using Doubles = typename LaneVectors<kLanes>::Doubles;
  using Counts = typename LaneVectors<kLanes>::Counts;
  Doubles qx, qy, qz;
  for (size_t q = 0; q < kLanes; ++q) {
    const size_t row = q < m ? q : 0;
    qx[q] = queries[3 * row];
    qy[q] = queries[3 * row + 1];
    qz[q] = queries[3 * row + 2];
  }
  std::array<Doubles, kSmallSetSize> d;
  std::array<Counts, kSmallSetSize> place;
  for (size_t j = 0; j < n; ++j) {
    const Doubles dx = qx - xyz[3 * j], dy = qy - xyz[3 * j + 1], dz = qz - xyz[3 * j + 2];
    d[j] = dx * dx + dy * dy + dz * dz;  // squared_distance()'s rounding
    place[j] = Counts{} + static_cast<int64_t>(j);
  }
  // A point's place in (distance, position) order: start from its position, as if every earlier
  // point ordered before it; each pair then moves the later point forward and the earlier one back
  // when the later one is strictly nearer (a comparison is -1 where true, 0 where false).
  for (size_t a = 0; a < n; ++a) {
    Counts moved = Counts{};
    for (size_t b = a + 1; b < n; ++b) {
      const Counts later_nearer = d[b] < d[a];
      moved -= later_nearer;
      place[b] += later_nearer;
    }
    place[a] += moved;
  }
  // The places of a query's points are 0 .. n−1 without repeats: write all, keep the first k.
  std::array<Neighbor, kSmallSetSize> sorted;
  for (size_t q = 0; q < std::min(m, kLanes); ++q) {
    for (size_t j = 0; j < n; ++j) {
      sorted[static_cast<size_t>(place[j][q])] = {d[j][q], static_cast<int32_t>(j)};
    }
    std::copy_n(sorted.begin(), k, out + q * k);
  }
}

}  // namespace

DYNSCOPE_ISA_CLONES
void small_set_knn_batch(const double* xyz, size_t n, const double* queries, size_t m, size_t k,
                         Neighbor* out) {
  n = std::min(n, kSmallSetSize);
  m = std::min(m, kSmallSetBatch);
  k = std::min(k, n);
  if (m == 0 || k == 0) return;
  // One lane per query: all of them in one vector of 8 doubles where that is one register
  // (AVX-512); else four at a time, one AVX2 register (wide_vector_registers()).
  if (wide_vector_registers()) {
    knn_lanes<kSmallSetBatch>(xyz, n, queries, m, k, out);
    return;
  }
  constexpr size_t kHalf = kSmallSetBatch / 2;
  for (size_t q0 = 0; q0 < m; q0 += kHalf) {
    knn_lanes<kHalf>(xyz, n, queries + 3 * q0, m - q0, k, out + q0 * k);
  }
}

DYNSCOPE_ISA_CLONES
uint32_t leaf_candidates(const double* xyz, uint32_t n, const double* query, double max_sq_dist,
                         double* d) {
  n = std::min(n, 32u);
  const double qx = query[0], qy = query[1], qz = query[2];
  uint32_t mask = 0;
  for (uint32_t j = 0; j < n; ++j) {
    const double dx = qx - xyz[3 * j], dy = qy - xyz[3 * j + 1], dz = qz - xyz[3 * j + 2];
    d[j] = dx * dx + dy * dy + dz * dz;  // squared_distance()'s rounding
    mask |= static_cast<uint32_t>(d[j] <= max_sq_dist) << j;
  }
  return mask;
}

DYNSCOPE_ISA_CLONES
size_t rank_nearest(const double* d, const int32_t* index, size_t n, size_t k, double max_sq_dist,
                    Neighbor* out) {
  // The indices ascend with the position, so position order is index order.
  return rank_by_position(d, index, std::min(n, kSmallSetSize), k, max_sq_dist, out);
}

}  // namespace dynscope
