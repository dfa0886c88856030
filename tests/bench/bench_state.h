// The synthetic scene the model benchmarks run on: points on eight spheres in a row.
#pragma once

#include <cstdint>
#include <vector>

#include "engine/core/rng.h"
#include "engine/core/types.h"
#include "engine/model/point_state.h"

namespace dynscope {

/// Objects in make_bench_state's scene.
constexpr int kBenchObjects = 8;

/// Points on the surfaces of kBenchObjects spheres of radius 0.1 resting in a row (Physion-like
/// spacing), each moving a little between frames, with the object id per point (point i belongs to
/// object i mod kBenchObjects). Deterministic for a given `n` ≥ 1.
inline PointState make_bench_state(int n) {
  Rng rng(1);
  Points p(n, 3), prev(n, 3), prev2(n, 3);
  std::vector<int32_t> ids(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    const int o = i % kBenchObjects;
    Vec3 d(rng.normal(), rng.normal(), rng.normal());
    d.normalize();
    const Vec3 centre(0.25 * o, 0.1 * (o % 2), 0.1);
    p.row(i) = (centre + 0.1 * d).transpose();
    prev.row(i) = p.row(i) - Eigen::RowVector3d(0.002, 0, 0.001);
    prev2.row(i) = prev.row(i) - Eigen::RowVector3d(0.002, 0, 0.001);
    ids[static_cast<size_t>(i)] = o;
  }
  return PointState::from_positions(p, prev, prev2, ids);
}

}  // namespace dynscope
