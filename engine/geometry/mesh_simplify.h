// Vertex-clustering mesh simplification.
#pragma once

#include "engine/scene/mesh.h"

namespace dynscope {

/// Merges all face-referenced vertices falling in the same voxel of edge `voxel` (grid anchored
/// at the origin) into their mean, remaps faces, drops faces that became degenerate (repeated
/// vertex or zero area) or duplicated (same vertex triple, either winding), and drops vertices no
/// face uses. Output vertices follow the order of their first input vertex. Throws ValueError if
/// voxel <= 0 or the mesh is invalid (field "mesh").
Mesh simplify_vertex_clustering(const Mesh& mesh, double voxel);

}  // namespace dynscope
