// Area-weighted uniform sampling of points on a triangle mesh surface.
#pragma once

#include <cstdint>
#include <vector>

#include "engine/core/rng.h"
#include "engine/scene/mesh.h"

namespace dynscope {

/// Points sampled on a surface with the face each came from.
struct SurfaceSamples {
  Points points = Points(0, 3);  ///< `[S,3]`, same frame as the mesh.
  std::vector<int32_t> face;     ///< `[S]` face index of each sample.
};

/// Samples `count` points uniformly by area (faces chosen with probability ∝ area, uniform
/// barycentric inside). Deterministic for a given rng state. Throws ValueError for an empty or
/// zero-area mesh or a negative count.
SurfaceSamples sample_surface(const Mesh& mesh, int64_t count, Rng& rng);

}  // namespace dynscope
