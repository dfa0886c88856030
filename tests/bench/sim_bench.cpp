// Ground-truth generation benchmarks: scenes per second for movi-a and a Physion-like scenario.
//
// BM_Simulate: one scene (setup + Bullet rollout, no file) per iteration on one thread.
// BM_GenerateDataset: `dynscope generate` without the progress bar: kScenes scenes simulated on
// `jobs` threads and written as HDF5 files plus the manifest into a temporary directory. The
// scenes_per_second counter is the number to compare; HDF5 writing is serialised (one lock), the
// simulation runs in parallel.
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <filesystem>

#include "engine/core/rng.h"
#include "engine/sim/dataset.h"
#include "engine/sim/scenario.h"

namespace dynscope {
namespace {

constexpr int64_t kScenes = 16;
const char* const kScenarios[] = {"movi-a", "dominoes"};

void BM_Simulate(benchmark::State& state) {
  const std::string scenario = kScenarios[state.range(0)];
  uint64_t i = 0;
  for (auto _ : state) {
    const Scene scene = generate_scene(scenario, derive_seed(0, i++));
    benchmark::DoNotOptimize(scene.trajectories.data());
  }
  state.SetLabel(scenario);
  state.counters["scenes_per_second"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_Simulate)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_GenerateDataset(benchmark::State& state) {
  namespace fs = std::filesystem;
  DatasetOptions options;
  options.scenario = kScenarios[state.range(0)];
  options.jobs = static_cast<int>(state.range(1));
  options.count = kScenes;
  options.out_dir =
      (fs::temp_directory_path() / ("dynscope_sim_bench_" + std::to_string(getpid()))).string();
  for (auto _ : state) generate_dataset(options);
  fs::remove_all(options.out_dir);
  state.SetLabel(options.scenario + ", " + std::to_string(options.jobs) + " jobs");
  state.counters["scenes_per_second"] = benchmark::Counter(
      static_cast<double>(state.iterations() * kScenes), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_GenerateDataset)
    ->Args({0, 1})
    ->Args({0, 2})
    ->Args({1, 1})
    ->Args({1, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace dynscope

BENCHMARK_MAIN();
