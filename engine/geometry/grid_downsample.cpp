// Voxel-grid downsampling that keeps, per voxel, the input point nearest the voxel centre.
#include "engine/geometry/grid_downsample.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "engine/core/error.h"

namespace dynscope {
namespace {

// Voxel coordinates beyond this would not fit the 64-bit key (and would lose integer exactness).
constexpr double kMaxVoxelCoordinate = 4.0e15;

struct VoxelKey {
  int32_t object;
  int64_t x, y, z;
  bool operator==(const VoxelKey& o) const {
    return object == o.object && x == o.x && y == o.y && z == o.z;
  }
};

struct VoxelKeyHash {
  size_t operator()(const VoxelKey& k) const {
    uint64_t h = static_cast<uint64_t>(static_cast<uint32_t>(k.object));
    for (const int64_t v : {k.x, k.y, k.z}) {
      h ^= static_cast<uint64_t>(v) + 0x9e3779b97f4a7c15ULL + (h << 6) + (h >> 2);
    }
    return static_cast<size_t>(h);
  }
};

std::vector<int32_t> downsample(const Points& points, const std::vector<int32_t>* object_ids,
                                double voxel) {
  if (!std::isfinite(voxel) || voxel <= 0.0) {
    throw ValueError("voxel", "must be finite and positive, got " + std::to_string(voxel));
  }
  if (object_ids != nullptr && object_ids->size() != static_cast<size_t>(points.rows())) {
    throw ValueError("object_ids", "has " + std::to_string(object_ids->size()) + " entries for " +
                                       std::to_string(points.rows()) + " points");
  }
  // Open addressing with linear probing in a table at most half full, holding each voxel's kept
  // point (-1: empty); the points' keys and distances are stored once, per point.
  const auto n = static_cast<size_t>(points.rows());
  size_t capacity = 16;
  while (capacity < 2 * n) capacity *= 2;
  std::vector<int32_t> table(capacity, -1);
  const size_t mask = capacity - 1;
  std::vector<VoxelKey> keys(n);
  std::vector<double> sq(n);
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    if (!points.row(i).allFinite()) {
      throw ValueError("points", "point " + std::to_string(i) + " is not finite");
    }
    const Eigen::RowVector3d cell = (points.row(i) / voxel).array().floor();
    if (cell.cwiseAbs().maxCoeff() > kMaxVoxelCoordinate) {
      throw ValueError("voxel", "point " + std::to_string(i) +
                                    " is too far from the origin for "
                                    "voxel " +
                                    std::to_string(voxel));
    }
    const Eigen::RowVector3d centre = (cell.array() + 0.5) * voxel;
    const Eigen::RowVector3d d = points.row(i) - centre;
    const auto index = static_cast<int32_t>(i);
    const VoxelKey& key = keys[static_cast<size_t>(i)] =
        VoxelKey{object_ids != nullptr ? (*object_ids)[static_cast<size_t>(i)] : 0,
                 static_cast<int64_t>(cell.x()), static_cast<int64_t>(cell.y()),
                 static_cast<int64_t>(cell.z())};
    sq[static_cast<size_t>(i)] = d.x() * d.x() + d.y() * d.y() + d.z() * d.z();
    size_t h = VoxelKeyHash()(key) & mask;
    while (table[h] >= 0 && !(keys[static_cast<size_t>(table[h])] == key)) h = (h + 1) & mask;
    // Points arrive in ascending index order, so keeping the first on equal distance keeps the
    // lowest index.
    if (table[h] < 0 || sq[static_cast<size_t>(i)] < sq[static_cast<size_t>(table[h])]) {
      table[h] = index;
    }
  }
  // Ascending: each voxel marks the point it keeps, then the marks are read in order.
  std::vector<uint8_t> keep(n, 0);
  for (const int32_t kept_point : table) {
    if (kept_point >= 0) keep[static_cast<size_t>(kept_point)] = 1;
  }
  std::vector<int32_t> kept;
  for (size_t i = 0; i < keep.size(); ++i) {
    if (keep[i]) kept.push_back(static_cast<int32_t>(i));
  }
  return kept;
}

}  // namespace

std::vector<int32_t> grid_downsample(const Points& points, double voxel) {
  return downsample(points, nullptr, voxel);
}

std::vector<int32_t> grid_downsample_per_object(const Points& points,
                                                const std::vector<int32_t>& object_ids,
                                                double voxel) {
  return downsample(points, &object_ids, voxel);
}

}  // namespace dynscope
