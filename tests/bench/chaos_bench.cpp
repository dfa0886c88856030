// How sensitive ground truth is to its initial state: the part of a model's end error no model
// can remove. Every dynamic body of a movi-a trial is moved by δ in a random direction at
// frame 0, the trial is simulated again, and the two ground truths are compared on the model's
// points (sampling voxel 0.3, as the campaign's models) at the last frame: the mean point
// distance, which is what `dynscope eval` calls the end error.
//
// BM_TruthSensitivity/E: δ = 10^-E scene units (E = 0 stands for δ = 0, the determinism check),
// kScenes trials per iteration. Counters: end_error (mean over trials), median and p90, and
// frac_over_1 (share of trials whose two truths end more than one unit apart).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "engine/core/rng.h"
#include "engine/rollout/model_points.h"
#include "engine/sim/scenario.h"
#include "engine/sim/simulation.h"

namespace dynscope {
namespace {

constexpr int kScenes = 100;
constexpr uint64_t kSeed = 0x63686130ULL;  // trials drawn apart from every dataset's seeds

double end_distance(const Scene& a, const Scene& b, const ModelPoints& points) {
  const int last = a.num_frames() - 1;
  return (points.positions(a, last) - points.positions(b, last)).rowwise().norm().mean();
}

void BM_TruthSensitivity(benchmark::State& state) {
  const double delta = state.range(0) == 0 ? 0.0 : std::pow(10.0, -state.range(0));
  std::vector<double> errors;
  for (auto _ : state) {
    errors.clear();
    for (int i = 0; i < kScenes; ++i) {
      const uint64_t seed = derive_seed(kSeed, static_cast<uint64_t>(i));
      SimSetup setup = scenario_setup("movi-a", seed);
      const Scene truth = simulate(setup);
      Rng rng(derive_seed(kSeed ^ 1, static_cast<uint64_t>(i)));
      for (BodySpec& body : setup.bodies) {
        if (body.object.mass <= 0) continue;
        const Vec3 direction = Vec3(rng.normal(), rng.normal(), rng.normal()).normalized();
        body.pose.position += delta * direction;
      }
      const Scene moved = simulate(setup);
      SamplingOptions sampling;
      sampling.voxel = 0.3;
      errors.push_back(end_distance(truth, moved, build_model_points(truth, sampling)));
    }
  }
  std::sort(errors.begin(), errors.end());
  double sum = 0.0;
  int over = 0;
  for (double e : errors) {
    sum += e;
    over += e > 1.0 ? 1 : 0;
  }
  state.counters["end_error"] = sum / static_cast<double>(errors.size());
  state.counters["median"] = errors[errors.size() / 2];
  state.counters["p90"] = errors[errors.size() * 9 / 10];
  state.counters["frac_over_1"] = static_cast<double>(over) / static_cast<double>(errors.size());
  state.SetLabel("movi-a, " + std::to_string(kScenes) + " trials, delta " +
                 (delta == 0.0 ? std::string("0") : "1e-" + std::to_string(state.range(0))));
}
BENCHMARK(BM_TruthSensitivity)
    ->DenseRange(0, 4)
    ->Iterations(1)
    ->Unit(benchmark::kSecond)
    ->UseRealTime();

}  // namespace
}  // namespace dynscope

BENCHMARK_MAIN();
