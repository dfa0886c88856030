// Model speed: one rollout step split into neighbour search (hierarchy), network and pose fitting,
// for 1k, 3k and 10k points and each model kind (pointconv, gnn, flat).
#include <benchmark/benchmark.h>
#include <sys/resource.h>
#include <torch/torch.h>

#include <string>
#include <vector>

#include "engine/core/rng.h"
#include "engine/geometry/kabsch.h"
#include "engine/model/dynamics_model.h"
#include "engine/model/model_config.h"
#include "engine/model/point_state.h"

namespace dynscope {
namespace {

constexpr int kObjects = 8;

// Points on the surfaces of kObjects unit spheres resting in a row (Physion-like spacing), each
// moving a little between frames, with the object id per point.
PointState make_state(int n) {
  Rng rng(1);
  Points p(n, 3), prev(n, 3), prev2(n, 3);
  std::vector<int32_t> ids(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    const int o = i % kObjects;
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

ModelConfig config_for(int kind) {
  ModelConfig c = ModelConfig::preset("physion");
  c.kind = static_cast<ModelKind>(kind);
  return c;
}

// Arguments: {points, model kind (0 pointconv, 1 gnn, 2 flat)}.
void apply_args(benchmark::internal::Benchmark* b) {
  for (int kind : {0, 1, 2}) {
    for (int n : {1000, 3000, 10000}) b->Args({n, kind});
  }
  b->ArgNames({"points", "kind"})->Unit(benchmark::kMillisecond)->UseRealTime();
}

void BM_NeighbourSearch(benchmark::State& state) {
  torch::set_num_threads(2);
  const PointState s = make_state(static_cast<int>(state.range(0)));
  DynamicsModel model(config_for(static_cast<int>(state.range(1))));
  for (auto _ : state) benchmark::DoNotOptimize(model->build_hierarchy(s));
  state.SetLabel(to_string(model->config().kind));
}
BENCHMARK(BM_NeighbourSearch)->Apply(apply_args);

void BM_Network(benchmark::State& state) {
  torch::set_num_threads(2);
  const PointState s = make_state(static_cast<int>(state.range(0)));
  DynamicsModel model(config_for(static_cast<int>(state.range(1))));
  model->eval();
  const ModelInput input = make_model_input(s, model->build_hierarchy(s));
  torch::NoGradGuard no_grad;
  for (auto _ : state) benchmark::DoNotOptimize(model->predict_positions(input));
  state.SetLabel(to_string(model->config().kind));
}
BENCHMARK(BM_Network)->Apply(apply_args);

void BM_PoseFitting(benchmark::State& state) {
  const PointState s = make_state(static_cast<int>(state.range(0)));
  std::vector<Points> per_object(kObjects);
  for (int o = 0; o < kObjects; ++o) {
    std::vector<Eigen::Index> rows;
    for (Eigen::Index i = 0; i < s.position.rows(); ++i) {
      if (s.object_ids[static_cast<size_t>(i)] == o) rows.push_back(i);
    }
    per_object[static_cast<size_t>(o)] = s.position(rows, Eigen::all);
  }
  for (auto _ : state) {
    for (const Points& pts : per_object) benchmark::DoNotOptimize(fit_rigid_transform(pts, pts));
  }
}
BENCHMARK(BM_PoseFitting)
    ->Arg(1000)
    ->Arg(3000)
    ->Arg(10000)
    ->ArgName("points")
    ->Unit(benchmark::kMillisecond);

// A whole rollout step as `dynscope rollout` runs it: hierarchy, network, then one Kabsch fit per
// object; frames per second are the inverse of the time per iteration.
void BM_RolloutStep(benchmark::State& state) {
  torch::set_num_threads(2);
  const PointState s = make_state(static_cast<int>(state.range(0)));
  DynamicsModel model(config_for(static_cast<int>(state.range(1))));
  model->eval();
  for (auto _ : state) {
    const Points next = model->predict_next(s);
    for (int o = 0; o < kObjects; ++o) {
      std::vector<Eigen::Index> rows;
      for (Eigen::Index i = 0; i < next.rows(); ++i) {
        if (s.object_ids[static_cast<size_t>(i)] == o) rows.push_back(i);
      }
      benchmark::DoNotOptimize(
          fit_rigid_transform(s.position(rows, Eigen::all), next(rows, Eigen::all)));
    }
  }
  state.counters["fps"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  // Process-wide high-water mark: runs go from small to large, so it bounds this run's peak.
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  state.counters["peak_rss_MiB"] = static_cast<double>(usage.ru_maxrss) / 1024.0;
  state.SetLabel(to_string(model->config().kind));
}
BENCHMARK(BM_RolloutStep)->Apply(apply_args);

}  // namespace
}  // namespace dynscope

BENCHMARK_MAIN();
