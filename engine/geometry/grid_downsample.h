// Grid (voxel) downsampling that keeps real input points: one per occupied voxel.
#pragma once

#include <cstdint>
#include <vector>

#include "engine/core/types.h"

namespace dynscope {

/// For every occupied voxel of edge `voxel` (grid anchored at the origin), keeps the index of the
/// input point nearest the voxel centre (ties: lowest index). Returns kept indices ascending.
/// Throws ValueError if voxel <= 0, a point is not finite, or a point is beyond ~4e15 voxels.
std::vector<int32_t> grid_downsample(const Points& points, double voxel);

/// Same, independently per object: voxels never mix points of different `object_ids` (`[N]`).
/// Throws ValueError as above, or if `object_ids` does not have one entry per point.
std::vector<int32_t> grid_downsample_per_object(const Points& points,
                                                const std::vector<int32_t>& object_ids,
                                                double voxel);

}  // namespace dynscope
