// small_set_knn: rank every distance of a small set. Compiled with -O3 (the ranking loops
// vectorise) and -ffp-contract=off (distances round as squared_distance()); see CMakeLists.txt.
#include "engine/geometry/small_set_knn.h"

#include <algorithm>
#include <array>

#include "engine/core/isa_clones.h"

namespace dynscope {

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
  // Point i's place among the points within the limit: those before it in (distance, index)
  // order, the indices being the positions. A point beyond the limit is farther than every point
  // within it, so it never counts.
  size_t count = 0;
  for (size_t i = 0; i < n; ++i) {
    const double di = d[i];
    if (!(di <= max_sq_dist)) continue;
    ++count;
    size_t place = 0;
    for (size_t j = 0; j < i; ++j) place += d[j] <= di ? 1 : 0;
    for (size_t j = i + 1; j < n; ++j) place += d[j] < di ? 1 : 0;
    if (place < k) out[place] = {di, static_cast<int32_t>(i)};
  }
  return std::min(count, k);
}

DYNSCOPE_ISA_CLONES
size_t rank_nearest(const double* d, const int32_t* index, size_t n, size_t k, double max_sq_dist,
                    Neighbor* out) {
  n = std::min(n, kSmallSetSize);
  // As small_set_knn, ties broken by the given indices.
  size_t count = 0;
  for (size_t i = 0; i < n; ++i) {
    const double di = d[i];
    const int32_t ii = index[i];
    if (!(di <= max_sq_dist)) continue;
    ++count;
    int32_t place = 0;
    for (size_t j = 0; j < n; ++j) {
      place += static_cast<int32_t>(d[j] < di) |
               (static_cast<int32_t>(d[j] == di) & static_cast<int32_t>(index[j] < ii));
    }
    if (static_cast<size_t>(place) < k) out[place] = {di, ii};
  }
  return std::min(count, k);
}

}  // namespace dynscope
