// PLY and PCD export of a point state (position + object id per point) through PCL.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "engine/core/types.h"

namespace dynscope {

/// Writes binary PLY with one vertex element: x, y, z (float32, `points` `[N,3]` rounded) and
/// label (uint32, the object id), atomically (temporary file + rename). Throws ValueError on a
/// size mismatch, no points or a negative id, IoError if the file cannot be written.
void export_points_ply(const std::string& path, const Points& points,
                       const std::vector<int32_t>& object_ids);

/// Writes binary PCD with fields x y z (float32) and label (uint32), atomically. Same errors as
/// export_points_ply.
void export_points_pcd(const std::string& path, const Points& points,
                       const std::vector<int32_t>& object_ids);

}  // namespace dynscope
