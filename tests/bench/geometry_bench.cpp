// Geometry benchmarks: exact kNN (our kd-tree in double, parallel) beside the PCL formulation it
// replaced, hierarchy building, grid downsampling, and brute-force baselines.
//
// Scene: 10 sphere surfaces (radius 0.5, 1.05 apart, so neighbouring objects are 0.05 apart)
// sampled uniformly by area, N points in total. kNN uses K = 16; the relational radius is 0.1.
// Rows named Pcl* run the previous formulation (PCL float kd-trees with double re-ranking, a new
// map of trees per list, serial queries; tests/bench/legacy_neighbors.h) on the same data in the
// same run, so speedups are ratios of the items_per_second columns. Rows taking a `threads`
// argument run on that many compute threads. The kd-tree rows answer every point as a query
// (tree building included); the brute-force rows (names ending _1000Queries) answer 1000 strided
// queries only, so compare queries per second, not times.
//
// Hierarchy rows: build_hierarchy with the Physion preset (4 levels, voxel 0.075, radius 0.1,
// K = 16) over points on 8 spheres of radius 0.1 in a row (as model_bench's make_state).
// KnnOtherObjectsRigidSteps: the level-0 relational list (K = 16, radius 0.1) over the consecutive
// rigid steps of model_bench's synthetic scene (tests/bench/bench_state.h), trees prebuilt.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <tuple>

#include "engine/core/allocator.h"
#include "engine/core/rng.h"
#include "engine/core/system_info.h"
#include "engine/core/threads.h"
#include "engine/geometry/grid_downsample.h"
#include "engine/geometry/neighbors.h"
#include "engine/geometry/surface_sampling.h"
#include "engine/model/hierarchy.h"
#include "engine/model/model_config.h"
#include "tests/bench/bench_state.h"
#include "tests/bench/legacy_neighbors.h"
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

// Runs the loop of `state` on state.range(1) compute threads, restoring the budget afterwards.
class ThreadScope {
 public:
  explicit ThreadScope(const benchmark::State& state) : saved_(compute_threads()) {
    set_compute_threads(static_cast<int>(state.range(1)));
  }
  ~ThreadScope() { set_compute_threads(saved_); }

 private:
  int saved_;
};

bool same_lists(const NeighborList& a, const NeighborList& b) {
  return a.index == b.index && a.mask == b.mask;
}

void BM_KnnSameObject(benchmark::State& state) {
  const Cloud& c = cloud(state.range(0));
  const ThreadScope threads(state);
  for (auto _ : state) {
    benchmark::DoNotOptimize(knn_same_object(c.points, c.ids, c.points, c.ids, kK));
  }
  state.SetItemsProcessed(state.iterations() * c.points.rows());
}

void BM_PclKnnSameObject(benchmark::State& state) {
  const Cloud& c = cloud(state.range(0));
  if (!same_lists(legacy::knn_same_object(c.points, c.ids, c.points, c.ids, kK),
                  knn_same_object(c.points, c.ids, c.points, c.ids, kK))) {
    state.SkipWithError("the PCL formulation gives different lists");
  }
  for (auto _ : state) {
    benchmark::DoNotOptimize(legacy::knn_same_object(c.points, c.ids, c.points, c.ids, kK));
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
  const ThreadScope threads(state);
  for (auto _ : state) {
    benchmark::DoNotOptimize(knn_other_objects(c.points, c.ids, c.points, c.ids, kK, kRadius));
  }
  state.SetItemsProcessed(state.iterations() * c.points.rows());
}

// The level-0 relational list of a rollout's consecutive rigid steps (model_bench's synthetic
// scene: eight spheres of radius 0.1 that turn and slide, two pairs through each other) over
// each step's prebuilt trees, as build_hierarchy searches it.
void BM_KnnOtherObjectsRigidSteps(benchmark::State& state) {
  const std::vector<PointState> steps =
      make_bench_rigid_steps(static_cast<int>(state.range(0)), kBenchRigidSteps);
  const ThreadScope threads(state);
  std::vector<ObjectIndex> trees;
  for (const PointState& s : steps) trees.emplace_back(s.position, s.object_ids);
  size_t step = 0, rows = 0;
  for (auto _ : state) {
    const size_t i = step++ % steps.size();
    benchmark::DoNotOptimize(
        knn_other_objects(steps[i].position, steps[i].object_ids, trees[i], kK, kRadius));
    rows += static_cast<size_t>(steps[i].position.rows());
  }
  state.SetItemsProcessed(static_cast<int64_t>(rows));
}

void BM_PclKnnOtherObjects(benchmark::State& state) {
  const Cloud& c = cloud(state.range(0));
  if (!same_lists(legacy::knn_other_objects(c.points, c.ids, c.points, c.ids, kK, kRadius),
                  knn_other_objects(c.points, c.ids, c.points, c.ids, kK, kRadius))) {
    state.SkipWithError("the PCL formulation gives different lists");
  }
  for (auto _ : state) {
    benchmark::DoNotOptimize(
        legacy::knn_other_objects(c.points, c.ids, c.points, c.ids, kK, kRadius));
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
  const ThreadScope threads(state);
  for (auto _ : state) benchmark::DoNotOptimize(knn_all(c.points, c.points, kK));
  state.SetItemsProcessed(state.iterations() * c.points.rows());
}

// Queries only, over a tree built once (what a level's shared index serves).
void BM_KnnAllPrebuiltTree(benchmark::State& state) {
  const Cloud& c = cloud(state.range(0));
  const ThreadScope threads(state);
  const KdIndex tree(c.points);
  for (auto _ : state) benchmark::DoNotOptimize(knn_all(c.points, tree, kK));
  state.SetItemsProcessed(state.iterations() * c.points.rows());
}

// Building the tree alone (what BM_KnnAll adds to BM_KnnAllPrebuiltTree).
void BM_KdIndexBuild(benchmark::State& state) {
  const Cloud& c = cloud(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(KdIndex(c.points).size());
  state.SetItemsProcessed(state.iterations() * c.points.rows());
}

// The same queries one search per point (KdIndex::knn, parallel over points), as knn_all answered
// a tree's own points before the leaf-batched search (KdIndex::knn_self).
void BM_KnnAllPrebuiltTreePerQuery(benchmark::State& state) {
  const Cloud& c = cloud(state.range(0));
  const ThreadScope threads(state);
  const KdIndex tree(c.points);
  const Eigen::Index n = c.points.rows();
  for (auto _ : state) {
    IndexMatrix index(n, kK);
#pragma omp parallel num_threads(static_cast <int>(state.range(1)))
    {
      std::vector<Neighbor> found;
#pragma omp for schedule(dynamic, 64)
      for (Eigen::Index i = 0; i < n; ++i) {
        tree.knn(c.points.row(i).transpose(), kK, found);
        for (size_t j = 0; j < found.size(); ++j) {
          index(i, static_cast<Eigen::Index>(j)) = found[j].index;
        }
      }
    }
    benchmark::DoNotOptimize(index.data());
  }
  state.SetItemsProcessed(state.iterations() * n);
}

void BM_PclKnnAll(benchmark::State& state) {
  const Cloud& c = cloud(state.range(0));
  if (!same_lists(legacy::knn_all(c.points, c.points, kK), knn_all(c.points, c.points, kK))) {
    state.SkipWithError("the PCL formulation gives different lists");
  }
  for (auto _ : state) benchmark::DoNotOptimize(legacy::knn_all(c.points, c.points, kK));
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

// Points on 8 spheres of radius 0.1 in a row (model_bench's make_state) and their object ids.
const Cloud& spheres(int64_t n) {
  static std::map<int64_t, Cloud> cache;
  auto it = cache.find(n);
  if (it != cache.end()) return it->second;
  Cloud c;
  c.points.resize(n, 3);
  Rng rng(1);
  for (Eigen::Index i = 0; i < n; ++i) {
    const int o = static_cast<int>(i % 8);
    Vec3 d(rng.normal(), rng.normal(), rng.normal());
    d.normalize();
    c.points.row(i) = (Vec3(0.25 * o, 0.1 * (o % 2), 0.1) + 0.1 * d).transpose();
    c.ids.push_back(o);
  }
  return cache.emplace(n, std::move(c)).first->second;
}

HierarchyOptions physion_options() {
  return HierarchyOptions::from_config(ModelConfig::preset("physion"));
}

bool same_hierarchy(const Hierarchy& a, const Hierarchy& b) {
  if (a.num_levels() != b.num_levels()) return false;
  for (size_t l = 0; l < a.levels.size(); ++l) {
    const HierarchyLevel& x = a.levels[l];
    const HierarchyLevel& y = b.levels[l];
    if (x.kept != y.kept || x.points != y.points || x.object_ids != y.object_ids ||
        !same_lists(x.same, y.same) || !same_lists(x.relational, y.relational) ||
        !same_lists(x.down, y.down) || !same_lists(x.up, y.up)) {
      return false;
    }
  }
  return true;
}

void BM_BuildHierarchy(benchmark::State& state) {
  const Cloud& c = spheres(state.range(0));
  const ThreadScope threads(state);
  const HierarchyOptions o = physion_options();
  for (auto _ : state) benchmark::DoNotOptimize(build_hierarchy(c.points, c.ids, o));
  state.SetItemsProcessed(state.iterations() * c.points.rows());
}

void BM_PclBuildHierarchy(benchmark::State& state) {
  const Cloud& c = spheres(state.range(0));
  const HierarchyOptions o = physion_options();
  if (!same_hierarchy(legacy::build_hierarchy(c.points, c.ids, o),
                      build_hierarchy(c.points, c.ids, o))) {
    state.SkipWithError("the PCL formulation gives a different hierarchy");
  }
  for (auto _ : state) benchmark::DoNotOptimize(legacy::build_hierarchy(c.points, c.ids, o));
  state.SetItemsProcessed(state.iterations() * c.points.rows());
}

// Arguments {points, threads} for the library rows; the Pcl rows are serial by construction.
void library_args(benchmark::internal::Benchmark* b) {
  for (const int64_t n : {10000, 100000}) {
    for (const int64_t t : {1, 2}) b->Args({n, t});
  }
  b->ArgNames({"points", "threads"})->Unit(benchmark::kMillisecond)->UseRealTime();
}

void serial_args(benchmark::internal::Benchmark* b) {
  b->Arg(10000)->Arg(100000)->ArgName("points")->Unit(benchmark::kMillisecond)->UseRealTime();
}

void hierarchy_args(benchmark::internal::Benchmark* b) {
  for (const int64_t n : {3000, 10000}) {
    for (const int64_t t : {1, 2}) b->Args({n, t});
  }
  b->ArgNames({"points", "threads"})->Unit(benchmark::kMillisecond)->UseRealTime();
}

BENCHMARK(BM_KnnAll)->Apply(library_args);
BENCHMARK(BM_KnnAllPrebuiltTree)->Apply(library_args);
BENCHMARK(BM_KnnAllPrebuiltTreePerQuery)->Apply(library_args);
BENCHMARK(BM_KdIndexBuild)->Apply(serial_args);
BENCHMARK(BM_PclKnnAll)->Apply(serial_args);
BENCHMARK(BM_BruteForceKnnAll_1000Queries)->Apply(serial_args);
BENCHMARK(BM_KnnSameObject)->Apply(library_args);
BENCHMARK(BM_PclKnnSameObject)->Apply(serial_args);
BENCHMARK(BM_BruteForceKnnSameObject_1000Queries)->Apply(serial_args);
BENCHMARK(BM_KnnOtherObjects)->Apply(library_args);
BENCHMARK(BM_KnnOtherObjectsRigidSteps)
    ->Args({3000, 1})
    ->Args({3000, 2})
    ->ArgNames({"points", "threads"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_PclKnnOtherObjects)->Apply(serial_args);
BENCHMARK(BM_BruteForceKnnOtherObjects_1000Queries)->Apply(serial_args);
BENCHMARK(BM_BuildHierarchy)->Apply(hierarchy_args);
BENCHMARK(BM_PclBuildHierarchy)
    ->Arg(3000)
    ->Arg(10000)
    ->ArgName("points")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_GridDownsamplePerObject)->Apply(serial_args);
BENCHMARK(BM_BaselineMapGridDownsamplePerObject)->Apply(serial_args);

}  // namespace
}  // namespace dynscope

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  // The heap settings of the programs that build these lists (they run LibTorch, which sets
  // them): with glibc's defaults every freshly built tree is faulted in anew, 40 ms of a 100k
  // point knn_all on one thread.
  dynscope::configure_allocator();
  // Torch-free, so the machine context without the LibTorch lines of bench_context.cpp.
  for (const auto& [key, value] : dynscope::system_context()) {
    benchmark::AddCustomContext(key, value);
  }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
