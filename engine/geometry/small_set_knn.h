// The k nearest of a small point set by ranking every distance (internal to KdIndex).
#pragma once

#include <cstddef>
#include <cstdint>

#include "engine/geometry/kdtree_index.h"

namespace dynscope {

/// Largest set small_set_knn() answers, and the size up to which KdIndex builds no tree: up to
/// here computing and ranking every distance is faster than descending a tree (K = 16, points on
/// spheres, 3,000 queries, one thread: 3–4× at 20 points, 1.6–2× at 26, 1.1–1.7× at 48, level or
/// slower from 64; README, "Small sets ranked instead of searched").
constexpr size_t kSmallSetSize = 48;

/// Writes to `out` the min(k, count) points of `xyz` (`n` <= kSmallSetSize points, row-major
/// x, y, z) nearest to `query` among the `count` whose squared distance is <= `max_sq_dist`,
/// sorted by (squared_distance(query, point), index), and returns how many it wrote. Equal to a
/// brute-force sort: every distance rounds as squared_distance() (no contraction into FMA), and a
/// point's place is the number of points ordering before it, counted by branch-free loops that
/// vectorise (cloned for x86-64-v4, v3 and the baseline).
size_t small_set_knn(const double* xyz, size_t n, const Vec3& query, size_t k, double max_sq_dist,
                     Neighbor* out);

/// Queries small_set_knn_batch() answers together.
constexpr size_t kSmallSetBatch = KdIndex::kBatchRows;

/// small_set_knn() without a distance limit for `m` <= kSmallSetBatch queries at once (`queries`
/// row-major x, y, z): writes query i's min(k, n) nearest to out[i·min(k, n) ...], the same lists
/// as one small_set_knn() per query. The queries are the vector lanes, so every pair of points is
/// compared once for all of them: several times faster than one call per query when whole objects
/// are queried against a small set (a coarse level's up list).
void small_set_knn_batch(const double* xyz, size_t n, const double* queries, size_t m, size_t k,
                         Neighbor* out);

/// Writes the squared distances from `query` to the `n` <= 32 points of `xyz` (row-major x, y, z)
/// to `d`, rounded as squared_distance(), and returns a mask with bit j set where d[j] <=
/// `max_sq_dist`: a kd-tree leaf's candidates, without a branch per point (cloned like the rest).
uint32_t leaf_candidates(const double* xyz, uint32_t n, const double* query, double max_sq_dist,
                         double* d);

/// Writes to `out` the min(k, count) of `n` <= kSmallSetSize candidates (squared distance `d[j]`,
/// index `index[j]`) among the `count` with d[j] <= `max_sq_dist`, sorted by (distance, index),
/// and returns how many it wrote: the ranking small_set_knn() uses, for candidates whose distances
/// are already computed (a kd-tree leaf's). Indices must ascend (index[j] < index[j + 1]), so
/// that ties resolve by position as in small_set_knn().
size_t rank_nearest(const double* d, const int32_t* index, size_t n, size_t k, double max_sq_dist,
                    Neighbor* out);

}  // namespace dynscope
