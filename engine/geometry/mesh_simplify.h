// Vertex-clustering mesh simplification.
#pragma once

#include "engine/scene/mesh.h"

namespace dynscope {

/// Merges all vertices falling in the same voxel of edge `voxel` (grid anchored at the origin)
/// into their mean, remaps faces, and drops faces that became degenerate or duplicated.
/// Throws ValueError if voxel <= 0.
Mesh simplify_vertex_clustering(const Mesh& mesh, double voxel);

}  // namespace dynscope
