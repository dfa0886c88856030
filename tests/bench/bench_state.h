// The synthetic scene the model benchmarks run on: points on eight spheres in a row.
#pragma once

#include <algorithm>
#include <cmath>
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
/// object i mod kBenchObjects); `scale` > 1 gives the same scene that many times larger (radii,
/// places and motion). Deterministic for a given `n` ≥ 1 and `scale`.
inline PointState make_bench_state(int n, double scale = 1.0) {
  Rng rng(1);
  Points p(n, 3), prev(n, 3), prev2(n, 3);
  std::vector<int32_t> ids(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    const int o = i % kBenchObjects;
    Vec3 d(rng.normal(), rng.normal(), rng.normal());
    d.normalize();
    const Vec3 centre(0.25 * o, 0.1 * (o % 2), 0.1);
    p.row(i) = scale * (centre + 0.1 * d).transpose();
    prev.row(i) = p.row(i) - scale * Eigen::RowVector3d(0.002, 0, 0.001);
    prev2.row(i) = prev.row(i) - scale * Eigen::RowVector3d(0.002, 0, 0.001);
    ids[static_cast<size_t>(i)] = o;
  }
  return PointState::from_positions(p, prev, prev2, ids);
}

/// The `scale` of make_bench_state(n, scale) whose points lie `spacing` apart on average (each
/// sphere's area shared equally by its points). At n = 3000 the unscaled spheres hold their points
/// 0.018 apart, seven times denser in area than the Physion-like scenes sampled at 0.05.
inline double bench_scale_for_spacing(int n, double spacing) {
  const double per_object = static_cast<double>(n) / kBenchObjects;
  return spacing * std::sqrt(per_object / (4.0 * 3.14159265358979323846)) / 0.1;
}

/// Steps of a rollout the rigid-step benchmark rows cycle through.
constexpr int kBenchRigidSteps = 16;

/// `steps` consecutive states of make_bench_state(n)'s scene in which every sphere turns and slides
/// as a rigid body (0.05 rad and up to 0.01 per frame), each point written as R·rest + t the way a
/// rollout's rigid projection writes it: what a rollout's HierarchyCache sees.
inline std::vector<PointState> make_bench_rigid_steps(int n, int steps, double scale = 1.0) {
  const PointState s = make_bench_state(n, scale);
  Rng rng(2);
  std::vector<Vec3> centre(kBenchObjects, Vec3::Zero()), axis(kBenchObjects), velocity;
  std::vector<int> count(kBenchObjects, 0);
  for (int i = 0; i < n; ++i) {
    centre[static_cast<size_t>(s.object_ids[static_cast<size_t>(i)])] += s.position.row(i);
    ++count[static_cast<size_t>(s.object_ids[static_cast<size_t>(i)])];
  }
  for (int o = 0; o < kBenchObjects; ++o) {
    centre[static_cast<size_t>(o)] /= std::max(1, count[static_cast<size_t>(o)]);
    axis[static_cast<size_t>(o)] = Vec3(rng.normal(), rng.normal(), rng.normal()).normalized();
    velocity.emplace_back(scale * 0.01 * (o % 3 - 1), scale * 0.005 * (o % 2), 0.0);
  }
  std::vector<Points> frames;
  for (int f = 0; f < steps + 2; ++f) {
    Points p(n, 3);
    for (int i = 0; i < n; ++i) {
      const auto o = static_cast<size_t>(s.object_ids[static_cast<size_t>(i)]);
      const Pose pose{centre[o] + velocity[o] * f, Quat(Eigen::AngleAxisd(0.05 * f, axis[o]))};
      p.row(i) = pose.apply(Vec3(s.position.row(i).transpose() - centre[o])).transpose();
    }
    frames.push_back(std::move(p));
  }
  std::vector<PointState> out;
  for (int f = 0; f < steps; ++f) {
    out.push_back(PointState::from_positions(frames[static_cast<size_t>(f + 2)],
                                             frames[static_cast<size_t>(f + 1)],
                                             frames[static_cast<size_t>(f)], s.object_ids));
  }
  return out;
}

}  // namespace dynscope
