// Geometry benchmarks: kd-tree kNN and grid downsampling against brute-force baselines.
//
// Scene: 10 sphere surfaces (radius 0.5, 1.05 apart, so neighbouring objects are 0.05 apart)
// sampled uniformly by area, N points in total. kNN uses K = 16; the relational radius is 0.1.
// The kd-tree benchmarks answer every point as a query (tree building included); the brute-force
// benchmarks (names ending _1000Queries) answer 1000 strided queries only, so compare the
// items_per_second columns (queries per second), not the times. Grid downsampling is compared
// with a std::map keyed by cell (the straightforward version) over the same points.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>

#include "engine/core/rng.h"
#include "engine/geometry/grid_downsample.h"
#include "engine/geometry/neighbors.h"
#include "engine/geometry/surface_sampling.h"
#include "tests/geometry/reference_neighbors.h"

namespace dynscope {
namespace {

constexpr int kK = 16;
constexpr double kRadius = 0.1;
constexpr double kVoxel = 0.05;
constexpr Eigen::Index kBruteForceQueries = 1000;

struct Cloud {
  Points points = Points(0, 3);
  std::vector<int32_t> ids;
};

const Cloud& cloud(int64_t n) {
  static std::map<int64_t, Cloud> cache;
  auto it = cache.find(n);
  if (it != cache.end()) return it->second;
  Cloud c;
  c.points.resize(n, 3);
  const Mesh sphere = make_sphere_mesh(0.5, 16, 32);
  Rng rng(1234);
  Eigen::Index row = 0;
  for (int o = 0; o < 10; ++o) {
    const int64_t count = n / 10 + (o < n % 10 ? 1 : 0);
    const SurfaceSamples s = sample_surface(sphere, count, rng);
    const Eigen::RowVector3d centre(1.05 * (o % 5), 1.05 * (o / 5), 0.0);
    for (Eigen::Index i = 0; i < s.points.rows(); ++i, ++row) {
      c.points.row(row) = s.points.row(i) + centre;
      c.ids.push_back(o);
    }
  }
  return cache.emplace(n, std::move(c)).first->second;
}

// A strided subset of the queries, spread over all objects.
Cloud query_subset(const Cloud& c) {
  const Eigen::Index m = std::min(kBruteForceQueries, c.points.rows());
  const Eigen::Index stride = c.points.rows() / m;
  Cloud q;
  q.points.resize(m, 3);
  for (Eigen::Index i = 0; i < m; ++i) {
    q.points.row(i) = c.points.row(i * stride);
    q.ids.push_back(c.ids[static_cast<size_t>(i * stride)]);
  }
  return q;
}

void BM_KnnSameObject(benchmark::State& state) {
  const Cloud& c = cloud(state.range(0));
  for (auto _ : state) {
    benchmark::DoNotOptimize(knn_same_object(c.points, c.ids, c.points, c.ids, kK));
  }
  state.SetItemsProcessed(state.iterations() * c.points.rows());
}

void BM_BruteForceKnnSameObject_1000Queries(benchmark::State& state) {
  const Cloud& c = cloud(state.range(0));
  const Cloud q = query_subset(c);
  for (auto _ : state) {
    benchmark::DoNotOptimize(reference::brute_force_knn(q.points, q.ids, c.points, c.ids, kK,
                                                        reference::Relation::kSameObject));
  }
  state.SetItemsProcessed(state.iterations() * q.points.rows());
}

void BM_KnnOtherObjects(benchmark::State& state) {
  const Cloud& c = cloud(state.range(0));
  for (auto _ : state) {
    benchmark::DoNotOptimize(knn_other_objects(c.points, c.ids, c.points, c.ids, kK, kRadius));
  }
  state.SetItemsProcessed(state.iterations() * c.points.rows());
}

void BM_BruteForceKnnOtherObjects_1000Queries(benchmark::State& state) {
  const Cloud& c = cloud(state.range(0));
  const Cloud q = query_subset(c);
  for (auto _ : state) {
    benchmark::DoNotOptimize(reference::brute_force_knn(
        q.points, q.ids, c.points, c.ids, kK, reference::Relation::kOtherObject, kRadius));
  }
  state.SetItemsProcessed(state.iterations() * q.points.rows());
}

void BM_KnnAll(benchmark::State& state) {
  const Cloud& c = cloud(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(knn_all(c.points, c.points, kK));
  state.SetItemsProcessed(state.iterations() * c.points.rows());
}

void BM_BruteForceKnnAll_1000Queries(benchmark::State& state) {
  const Cloud& c = cloud(state.range(0));
  const Cloud q = query_subset(c);
  for (auto _ : state) {
    benchmark::DoNotOptimize(
        reference::brute_force_knn(q.points, {}, c.points, {}, kK, reference::Relation::kAll));
  }
  state.SetItemsProcessed(state.iterations() * q.points.rows());
}

void BM_GridDownsamplePerObject(benchmark::State& state) {
  const Cloud& c = cloud(state.range(0));
  for (auto _ : state) {
    benchmark::DoNotOptimize(grid_downsample_per_object(c.points, c.ids, kVoxel));
  }
  state.SetItemsProcessed(state.iterations() * c.points.rows());
}

// Baseline: an ordered map from cell to the best point (the straightforward tree-map version).
void BM_BaselineMapGridDownsamplePerObject(benchmark::State& state) {
  const Cloud& c = cloud(state.range(0));
  for (auto _ : state) {
    std::map<std::tuple<int32_t, int64_t, int64_t, int64_t>, std::pair<double, int32_t>> best;
    for (Eigen::Index i = 0; i < c.points.rows(); ++i) {
      const Eigen::RowVector3d cell = (c.points.row(i) / kVoxel).array().floor();
      const Eigen::RowVector3d d = c.points.row(i) - (cell.array() + 0.5).matrix() * kVoxel;
      const std::pair<double, int32_t> candidate(d.squaredNorm(), static_cast<int32_t>(i));
      const auto key =
          std::make_tuple(c.ids[static_cast<size_t>(i)], static_cast<int64_t>(cell.x()),
                          static_cast<int64_t>(cell.y()), static_cast<int64_t>(cell.z()));
      auto [it, inserted] = best.try_emplace(key, candidate);
      if (!inserted && candidate < it->second) it->second = candidate;
    }
    std::vector<int32_t> kept;
    for (const auto& [key, b] : best) kept.push_back(b.second);
    std::sort(kept.begin(), kept.end());
    benchmark::DoNotOptimize(kept);
  }
  state.SetItemsProcessed(state.iterations() * c.points.rows());
}

BENCHMARK(BM_KnnSameObject)->Arg(10000)->Arg(100000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BruteForceKnnSameObject_1000Queries)
    ->Arg(10000)
    ->Arg(100000)
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_KnnOtherObjects)->Arg(10000)->Arg(100000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BruteForceKnnOtherObjects_1000Queries)
    ->Arg(10000)
    ->Arg(100000)
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_KnnAll)->Arg(10000)->Arg(100000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BruteForceKnnAll_1000Queries)->Arg(10000)->Arg(100000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GridDownsamplePerObject)->Arg(10000)->Arg(100000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BaselineMapGridDownsamplePerObject)
    ->Arg(10000)
    ->Arg(100000)
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace dynscope

BENCHMARK_MAIN();
