// Interaction-point neighbour lists for the mesh relational path (paper §3.2, no torch).
#pragma once

#include <cstdint>
#include <vector>

#include "engine/core/types.h"
#include "engine/geometry/neighbors.h"

namespace dynscope {

/// The three neighbourhoods of the mesh Relational PointConv. Interaction points are both ends of
/// every close sample pair of find_interaction_points (each (face, sample) once); a point acts as
/// sender for the faces paired with its face and as receiver for its own face.
struct MeshInteraction {
  Points points = Points(0, 3);     ///< `[I,3]` interaction points (world).
  std::vector<int32_t> face;        ///< `[I]` face each point lies on.
  std::vector<int32_t> object_ids;  ///< `[I]` object of that face.
  NeighborList face_vertices;  ///< Queries: interaction points; sources: vertices; the 3 corners
                               ///< of the point's face (layer 1, sender face → sender point).
  NeighborList senders;        ///< Queries: interaction points as receivers; sources: interaction
                         ///< points on faces paired with the query's face, k nearest (layer 2).
  NeighborList vertex_points;  ///< Queries: vertices; sources: interaction points on the faces that
                               ///< contain the vertex, all of them (layer 3, averaged).

  Eigen::Index size() const { return points.rows(); }
};

/// Finds interaction points between faces of different objects closer than `threshold` (`lattice`
/// samples per edge, more on faces longer than `spacing` allows when it is > 0, as in
/// find_interaction_points) and builds the three lists. A face's object is its first vertex's id.
/// Throws ValueError on inconsistent sizes or bad indices.
MeshInteraction build_mesh_interaction(const Points& vertices,
                                       const std::vector<int32_t>& vertex_object_ids,
                                       const Faces& faces, double threshold, int lattice, int k,
                                       double spacing = 0.0);

}  // namespace dynscope
