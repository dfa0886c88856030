// Model speed: one rollout step split into neighbour search (hierarchy), input tensors, network and
// pose fitting, for 1k, 3k and 10k points and each model kind (pointconv, gnn, flat), each on the
// fused ops (kernels cloned per instruction set), on the same ops with their baseline SSE2 kernels
// and on the unfused reference formulation in the same run; training steps of the default movi-a
// recipe model on a bundled scene; peak memory of training on 10k points; the rate of the object
// convolutions' fused op against the BLAS's at the same sizes; the mesh interaction lists beside
// their previous formulation.
#include <benchmark/benchmark.h>
#include <sys/resource.h>
#include <torch/torch.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "engine/geometry/kabsch.h"
#include "engine/io/scene_file.h"
#include "engine/model/checkpoint.h"
#include "engine/model/conv_implementation.h"
#include "engine/model/dynamics_model.h"
#include "engine/model/fused_point_conv.h"
#include "engine/model/mesh_interaction.h"
#include "engine/model/model_config.h"
#include "engine/model/point_state.h"
#include "engine/model/torch_runtime.h"
#include "engine/rollout/model_points.h"
#include "engine/rollout/rollout_runner.h"
#include "engine/train/adam_step.h"
#include "engine/train/train_options.h"
#include "tests/bench/bench_state.h"
#include "tests/bench/legacy_mesh_interaction.h"

namespace dynscope {
namespace {

// Threads of the inference rows: 2 (the machine's cores) unless DYNSCOPE_BENCH_THREADS says
// otherwise, e.g. 1 to measure on a machine whose other core is busy.
int bench_threads() {
  const char* env = std::getenv("DYNSCOPE_BENCH_THREADS");
  return env ? std::max(1, std::atoi(env)) : 2;
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

// Arguments: {points, model kind, implementation (use_implementation)}.
void apply_impl_args(benchmark::internal::Benchmark* b) {
  for (int kind : {0, 1, 2}) {
    for (int n : {1000, 3000, 10000}) {
      for (int impl : {0, 3, 2, 1}) b->Args({n, kind, impl});
    }
  }
  b->ArgNames({"points", "kind", "impl"})->Unit(benchmark::kMillisecond)->UseRealTime();
}

// Selects the formulation for one benchmark run and names it in the label.
// impl 0: the fused ops (kernels cloned per instruction set), 1: the unfused reference,
// 2: the fused ops on their baseline (SSE2) kernels, 3: the fused aggregation with the PointConv's
// WeightNet and embedding as LibTorch ops before it (ConvImplementation::kFusedComposed).
std::string use_implementation(int64_t arg, const ModelConfig& config) {
  const ConvImplementation impl = arg == 1   ? ConvImplementation::kUnfused
                                  : arg == 2 ? ConvImplementation::kFusedBaseline
                                  : arg == 3 ? ConvImplementation::kFusedComposed
                                             : ConvImplementation::kFused;
  set_conv_implementation(impl);
  return to_string(config.kind) + (arg == 1   ? " unfused"
                                   : arg == 2 ? " fused-baseline"
                                   : arg == 3 ? " fused-composed"
                                              : " fused");
}

void BM_NeighbourSearch(benchmark::State& state) {
  set_torch_threads(bench_threads());
  const PointState s = make_bench_state(static_cast<int>(state.range(0)));
  DynamicsModel model(config_for(static_cast<int>(state.range(1))));
  for (auto _ : state) benchmark::DoNotOptimize(model->build_hierarchy(s));
  state.SetLabel(to_string(model->config().kind));
}
BENCHMARK(BM_NeighbourSearch)->Apply(apply_args);

// Arguments {points, cache, density}: a rollout's consecutive rigid steps (make_bench_rigid_steps),
// the PointConv model, the hierarchy built without (0) and with (1) one HierarchyCache for the run;
// density 0 the benchmark's spheres, 1 the same scene scaled so that its points lie the
// Physion-like scenes' sampling voxel (0.05) apart (bench_scale_for_spacing).
void rigid_step_args(benchmark::internal::Benchmark* b) {
  for (int n : {1000, 3000, 10000}) {
    for (int cached : {0, 1}) b->Args({n, cached, 0});
  }
  for (int cached : {0, 1}) b->Args({3000, cached, 1});
  b->ArgNames({"points", "cache", "density"})->Unit(benchmark::kMillisecond)->UseRealTime();
}

// The rigid steps of rigid_step_args' arguments.
std::vector<PointState> rigid_steps_for(const benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const double scale = state.range(2) ? bench_scale_for_spacing(n, 0.05) : 1.0;
  return make_bench_rigid_steps(n, kBenchRigidSteps, scale);
}

void BM_NeighbourSearchRigidSteps(benchmark::State& state) {
  set_torch_threads(bench_threads());
  const std::vector<PointState> steps = rigid_steps_for(state);
  DynamicsModel model(config_for(0));
  HierarchyCache cache;
  HierarchyCache* use = state.range(1) ? &cache : nullptr;
  size_t step = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(model->build_hierarchy(steps[step++ % steps.size()], use));
  }
  if (use) {
    state.counters["reused"] = static_cast<double>(cache.reused_rows()) /
                               static_cast<double>(cache.reused_rows() + cache.searched_rows());
  }
}
BENCHMARK(BM_NeighbourSearchRigidSteps)->Apply(rigid_step_args);

// The previous conversion of a hierarchy's lists: to_tensors per list, then prepare() on its
// points (some twenty LibTorch ops per list), for BM_ModelInput's comparison row.
HierarchyTensors convert_then_prepare(const Hierarchy& h) {
  HierarchyTensors out;
  for (size_t l = 0; l < h.levels.size(); ++l) {
    const HierarchyLevel& level = h.levels[l];
    LevelTensors t;
    t.points = points_to_tensor(level.points);
    t.radius = level.radius;
    t.same = to_tensors(level.same);
    t.relational = to_tensors(level.relational);
    t.down = to_tensors(level.down);
    t.up = to_tensors(level.up);
    t.same.prepare(t.points, t.points);
    t.relational.prepare(t.points, t.points);
    if (l > 0) {
      t.down.prepare(t.points, out.levels.back().points);
      t.up.prepare(out.levels.back().points, t.points);
    }
    out.levels.push_back(std::move(t));
  }
  return out;
}

// The model's input tensors from a state and its hierarchy (part of every rollout step), at 3k
// points. Argument: 0 make_model_input (lists converted and prepared in one pass each), 1 the
// previous conversion (convert_then_prepare).
void BM_ModelInput(benchmark::State& state) {
  set_torch_threads(bench_threads());
  const PointState s = make_bench_state(3000);
  DynamicsModel model(config_for(0));
  const Hierarchy h = model->build_hierarchy(s);
  torch::NoGradGuard no_grad;
  for (auto _ : state) {
    if (state.range(0) == 0) {
      benchmark::DoNotOptimize(make_model_input(s, h));
    } else {
      benchmark::DoNotOptimize(convert_then_prepare(h));
    }
  }
  state.SetLabel(state.range(0) == 0 ? "one pass" : "convert, then prepare");
}
BENCHMARK(BM_ModelInput)
    ->Arg(0)
    ->Arg(1)
    ->ArgName("previous")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_Network(benchmark::State& state) {
  set_torch_threads(bench_threads());
  const PointState s = make_bench_state(static_cast<int>(state.range(0)));
  DynamicsModel model(config_for(static_cast<int>(state.range(1))));
  state.SetLabel(use_implementation(state.range(2), model->config()));
  model->eval();
  const ModelInput input = make_model_input(s, model->build_hierarchy(s));
  torch::NoGradGuard no_grad;
  for (auto _ : state) benchmark::DoNotOptimize(model->predict_positions(input));
  set_conv_implementation(ConvImplementation::kFused);
}
BENCHMARK(BM_Network)->Apply(apply_impl_args);

// The rate of the object convolutions' fused aggregation with its linear
// (point_conv_aggregate_mlp_linear, as inference runs it) at the sizes of one level of the rollout
// step at the sampling density (BM_RolloutStepRigidSteps with density 1: 3000, ~1290, ~620 and
// ~280 points, input widths 8, 16, 32 and 64, each with the 8-wide embedding; K = 16, J = 16,
// WeightNet hidden width 8), every neighbour valid, in GFLOP/s counted from those sizes: per
// neighbour the WeightNet (3·8 + 8·8 + 8·16 multiply-adds), the embedding (3·8 + 8·8) and its
// share of the aggregate (16·(C + 8)); per query the linear (C_out·16·(C + 8)). Beside it in the
// same run, BM_SgemmRate: LibTorch's matrix product at the same linear's sizes and at 1024³, the
// BLAS's rate on this machine.
struct AggregationSize {
  int64_t m, c, c_out;
};
constexpr AggregationSize kAggregationSizes[] = {
    {3000, 8, 8}, {1290, 16, 16}, {620, 32, 32}, {280, 64, 64}};
constexpr int64_t kAggK = 16, kAggJ = 16, kAggH = 8, kAggP = 8;

void BM_ObjectAggregationRate(benchmark::State& state) {
  set_torch_threads(bench_threads());
  const AggregationSize size = kAggregationSizes[state.range(0)];
  torch::manual_seed(1);
  const auto f = torch::TensorOptions().dtype(torch::kFloat32);
  // The queries' own points are the sources, as in a same-level list.
  const torch::Tensor features = torch::randn({size.m, size.c}, f);
  const torch::Tensor rel = torch::randn({size.m, kAggK, 3}, f);
  const torch::Tensor index =
      torch::randint(size.m, {size.m, kAggK}, torch::TensorOptions().dtype(torch::kInt64));
  EdgeMlps mlps;
  mlps.w1 = torch::randn({kAggH, 3}, f);
  mlps.b1 = torch::randn({kAggH}, f);
  mlps.w2 = torch::randn({kAggH, kAggH}, f);
  mlps.b2 = torch::randn({kAggH}, f);
  mlps.w3 = torch::randn({kAggJ, kAggH}, f);
  mlps.b3 = torch::randn({kAggJ}, f);
  mlps.e1 = torch::randn({kAggP, 3}, f);
  mlps.c1 = torch::randn({kAggP}, f);
  mlps.e2 = torch::randn({kAggP, kAggP}, f);
  mlps.c2 = torch::randn({kAggP}, f);
  const int64_t ct = size.c + kAggP;
  const torch::Tensor weight = torch::randn({size.c_out, kAggJ * ct}, f);
  torch::NoGradGuard no_grad;
  for (auto _ : state) {
    benchmark::DoNotOptimize(
        point_conv_aggregate_mlp_linear(features, rel, mlps, torch::Tensor(), index, weight));
  }
  const double per_edge =
      3 * kAggH + kAggH * kAggH + kAggH * kAggJ + 3 * kAggP + kAggP * kAggP + kAggJ * ct;
  const double per_query = static_cast<double>(size.c_out * kAggJ * ct);
  const double flops = 2.0 * static_cast<double>(size.m) * (kAggK * per_edge + per_query);
  state.counters["GFLOPS"] = benchmark::Counter(
      1e-9 * flops * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  state.SetLabel("M=" + std::to_string(size.m) + " C=" + std::to_string(size.c));
}
BENCHMARK(BM_ObjectAggregationRate)
    ->DenseRange(0, 3)
    ->ArgName("level")
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();

// LibTorch's matrix product [M, J·(C + 8)] × [J·(C + 8), C_out] at the sizes of
// BM_ObjectAggregationRate's levels (0-3), and 1024 × 1024 × 1024 (4).
void BM_SgemmRate(benchmark::State& state) {
  set_torch_threads(bench_threads());
  const bool square = state.range(0) == 4;
  const AggregationSize size = kAggregationSizes[square ? 0 : state.range(0)];
  const int64_t m = square ? 1024 : size.m, k = square ? 1024 : kAggJ * (size.c + kAggP),
                n = square ? 1024 : size.c_out;
  torch::manual_seed(1);
  const torch::Tensor a = torch::randn({m, k}), b = torch::randn({k, n});
  torch::NoGradGuard no_grad;
  for (auto _ : state) benchmark::DoNotOptimize(torch::mm(a, b));
  state.counters["GFLOPS"] = benchmark::Counter(
      2e-9 * static_cast<double>(m * k * n) * static_cast<double>(state.iterations()),
      benchmark::Counter::kIsRate);
  state.SetLabel(std::to_string(m) + "x" + std::to_string(k) + "x" + std::to_string(n));
}
BENCHMARK(BM_SgemmRate)
    ->DenseRange(0, 4)
    ->ArgName("shape")
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();

void BM_PoseFitting(benchmark::State& state) {
  const PointState s = make_bench_state(static_cast<int>(state.range(0)));
  std::vector<Points> per_object(kBenchObjects);
  for (int o = 0; o < kBenchObjects; ++o) {
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

// The rollout step's pose fitting: one Kabsch fit per object of make_bench_state's scene.
void fit_object_poses(const PointState& s, const Points& next) {
  for (int o = 0; o < kBenchObjects; ++o) {
    std::vector<Eigen::Index> rows;
    for (Eigen::Index i = 0; i < next.rows(); ++i) {
      if (s.object_ids[static_cast<size_t>(i)] == o) rows.push_back(i);
    }
    benchmark::DoNotOptimize(
        fit_rigid_transform(s.position(rows, Eigen::all), next(rows, Eigen::all)));
  }
}

// A whole rollout step as `dynscope rollout` runs it: hierarchy, network, then one Kabsch fit per
// object; frames per second are the inverse of the time per iteration.
void BM_RolloutStep(benchmark::State& state) {
  set_torch_threads(bench_threads());
  const PointState s = make_bench_state(static_cast<int>(state.range(0)));
  DynamicsModel model(config_for(static_cast<int>(state.range(1))));
  state.SetLabel(use_implementation(state.range(2), model->config()));
  model->eval();
  for (auto _ : state) {
    const Points next = model->predict_next(s);
    fit_object_poses(s, next);
  }
  state.counters["fps"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  set_conv_implementation(ConvImplementation::kFused);
}
BENCHMARK(BM_RolloutStep)->Apply(apply_impl_args);

// A whole rollout step (as BM_RolloutStep, fused ops) over consecutive rigid steps, without and
// with the rollout's HierarchyCache.
void BM_RolloutStepRigidSteps(benchmark::State& state) {
  set_torch_threads(bench_threads());
  const std::vector<PointState> steps = rigid_steps_for(state);
  DynamicsModel model(config_for(0));
  model->eval();
  HierarchyCache cache;
  HierarchyCache* use = state.range(1) ? &cache : nullptr;
  size_t step = 0;
  for (auto _ : state) {
    const PointState& s = steps[step++ % steps.size()];
    const Points next = model->predict_next(s, use);
    fit_object_poses(s, next);
  }
  state.counters["fps"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_RolloutStepRigidSteps)->Apply(rigid_step_args);

// Whole rollouts of the shipped Physion-like model on the bundled sample of each of the seven
// scenarios (`dynscope rollout` as it runs them: 3 observed frames, rigid projection), without (0)
// and with (1) the rollout's HierarchyCache; hierarchy_ms is the hierarchy's time per step (the
// step is predict_next's, split so that the hierarchy can be timed on its own).
// Unlike make_bench_rigid_steps, most objects here rest for most frames, as in Physion scenes.
void BM_PhysionRollouts(benchmark::State& state) {
  set_torch_threads(bench_threads());
  const std::string root = DYNSCOPE_SOURCE_DIR;
  const std::string checkpoint = root + "/assets/models/physion_pointconv_acc.pt";
  DynamicsModel model = load_checkpoint(checkpoint);
  model->eval();
  struct Case {
    Scene scene;
    ModelPoints points;
  };
  std::vector<Case> cases;
  for (const char* scenario :
       {"collide", "contain", "dominoes", "drop", "link", "roll", "support"}) {
    Case c;
    c.scene = read_scene(root + "/assets/scenes/" + scenario + "_0000.h5");
    c.points = build_model_points(c.scene, checkpoint_sampling(checkpoint, model->config()));
    cases.push_back(std::move(c));
  }
  const bool cached = state.range(0) != 0;
  double hierarchy_s = 0.0;
  int64_t frames = 0;
  for (auto _ : state) {
    for (const Case& c : cases) {
      HierarchyCache cache;
      const StepPredictor predict = [&](const PointState& s) {
        const auto start = std::chrono::steady_clock::now();
        const Hierarchy h = model->build_hierarchy(s, cached ? &cache : nullptr);
        hierarchy_s +=
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        torch::NoGradGuard no_grad;
        const torch::Tensor delta =
            model->predict_delta(make_model_input(s, h)).to(torch::kDouble).contiguous();
        ++frames;
        return Points(s.position + Eigen::Map<const Points>(delta.data_ptr<double>(), s.size(), 3));
      };
      RolloutOptions options;
      options.observed_frames = 3;
      benchmark::DoNotOptimize(run_rollout(c.scene, c.points, predict, options));
    }
  }
  state.counters["fps"] =
      benchmark::Counter(static_cast<double>(frames), benchmark::Counter::kIsRate);
  state.counters["hierarchy_ms"] =
      1e3 * hierarchy_s / static_cast<double>(std::max<int64_t>(1, frames));
  state.SetLabel(cached ? "cache" : "fresh");
}
BENCHMARK(BM_PhysionRollouts)
    ->Arg(0)
    ->Arg(1)
    ->ArgName("cache")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The mesh interaction lists (interaction points and their three neighbourhoods) of the bundled
// movi-a scenes as the campaign's faces-on recipe samples them (mesh vertices clustered at 0.3,
// K = 12), every frame of both scenes once per iteration; arguments {implementation (0: the
// previous formulation, tests/bench/legacy_mesh_interaction.h; 1: the library's), interaction
// threshold in hundredths}. points_per_frame counts the interaction points.
void BM_MeshInteraction(benchmark::State& state) {
  const std::string root = DYNSCOPE_SOURCE_DIR;
  SamplingOptions sampling;
  sampling.input = InputMode::kMesh;
  sampling.voxel = 0.3;
  struct Frame {
    Points vertices;
    std::vector<int32_t> ids;
    const Faces* faces;
  };
  std::vector<Scene> scenes;
  std::vector<ModelPoints> meshes;
  for (const char* name : {"movi-a_0000.h5", "movi-a_0001.h5"}) {
    scenes.push_back(read_scene(root + "/assets/scenes/" + name));
    meshes.push_back(build_model_points(scenes.back(), sampling));
  }
  std::vector<Frame> frames;
  for (size_t m = 0; m < scenes.size(); ++m) {
    for (int t = 0; t < scenes[m].num_frames(); ++t)
      frames.push_back(
          {meshes[m].positions(scenes[m], t), meshes[m].cloud.object_id, &meshes[m].faces});
  }
  const bool library = state.range(0) != 0;
  const double threshold = 0.01 * static_cast<double>(state.range(1));
  int64_t points = 0, built = 0;
  for (auto _ : state) {
    for (const Frame& f : frames) {
      const MeshInteraction mi =
          library ? build_mesh_interaction(f.vertices, f.ids, *f.faces, threshold, 3, 12)
                  : legacy::build_mesh_interaction(f.vertices, f.ids, *f.faces, threshold, 3, 12);
      points += mi.size();
      ++built;
      benchmark::DoNotOptimize(mi);
    }
  }
  state.counters["s_per_frame"] = benchmark::Counter(
      static_cast<double>(built), benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["points_per_frame"] =
      static_cast<double>(points) / static_cast<double>(std::max<int64_t>(1, built));
  state.SetLabel(std::string(library ? "library" : "previous formulation") + ", " +
                 std::to_string(frames.size()) + " frames, 1 thread");
}
BENCHMARK(BM_MeshInteraction)
    ->Args({0, 40})
    ->Args({1, 40})
    ->Args({0, 60})
    ->Args({1, 60})
    ->Args({0, 80})
    ->Args({1, 80})
    ->ArgNames({"impl", "threshold_cm"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The default movi-a recipe's model and a state of the first bundled movi-a scene, as training
// sees them (the recipe's sampling, frame 12).
struct TrainCase {
  DynamicsModel model{nullptr};
  PointState state;
  torch::Tensor truth;
};

TrainCase movi_train_case() {
  const std::string root = DYNSCOPE_SOURCE_DIR;
  const std::string recipe_file = root + "/assets/recipes/movi-a_pointconv_acc.json";
  std::ifstream in(recipe_file);
  std::stringstream text;
  text << in.rdbuf();
  TrainOptions recipe = TrainOptions::from_json(text.str(), recipe_file);
  recipe.resolve("movi-a");
  const Scene scene = read_scene(root + "/assets/scenes/movi-a_0000.h5");
  const ModelPoints points = build_model_points(scene, recipe.sampling);
  TrainCase c;
  torch::manual_seed(1);
  c.model = DynamicsModel(recipe.model);
  c.model->train();
  const int t = 12;
  c.state = PointState::from_positions(points.positions(scene, t), points.positions(scene, t - 1),
                                       points.positions(scene, t - 2), points.cloud.object_id);
  c.truth = points_to_tensor(points.positions(scene, t + 1));
  return c;
}

// One optimiser step: forward, Huber loss, backward, Adam. Arguments {impl, hierarchy,
// torch_adam}: with hierarchy = 1 the step also builds the example's hierarchy (what training does
// when the prefetch thread cannot hide it); torch_adam = 1 updates with LibTorch's Adam::step
// instead of the one-loop adam_step training uses.
void BM_TrainStep(benchmark::State& state) {
  set_torch_threads(1);
  TrainCase c = movi_train_case();
  state.SetLabel(use_implementation(state.range(0), c.model->config()) +
                 (state.range(1) ? " +hierarchy" : "") + (state.range(2) ? " +LibTorch Adam" : "") +
                 ", " + std::to_string(c.state.size()) + " points, 1 thread");
  torch::optim::Adam adam(c.model->parameters(), torch::optim::AdamOptions(5e-3));
  const ModelInput prepared = make_model_input(c.state, c.model->build_hierarchy(c.state));
  // The step's phases, in milliseconds per step: forward (with the loss), backward, optimiser.
  using Clock = std::chrono::steady_clock;
  double forward_s = 0, backward_s = 0, optimiser_s = 0;
  auto since = [](Clock::time_point t) {
    return std::chrono::duration<double>(Clock::now() - t).count();
  };
  for (auto _ : state) {
    const ModelInput input =
        state.range(1) ? make_model_input(c.state, c.model->build_hierarchy(c.state)) : prepared;
    auto t = Clock::now();
    adam.zero_grad();
    const torch::Tensor err = (c.model->predict_positions(input) - c.truth).to(torch::kFloat);
    const torch::Tensor loss = torch::nn::functional::huber_loss(err, torch::zeros_like(err));
    forward_s += since(t);
    t = Clock::now();
    loss.backward();
    backward_s += since(t);
    t = Clock::now();
    if (state.range(2)) {
      adam.step();
    } else {
      adam_step(adam);
    }
    optimiser_s += since(t);
  }
  const auto per_step = [&](double s) {
    return 1e3 * s / static_cast<double>(std::max<int64_t>(1, state.iterations()));
  };
  state.counters["forward_ms"] = per_step(forward_s);
  state.counters["backward_ms"] = per_step(backward_s);
  state.counters["optimiser_ms"] = per_step(optimiser_s);
  state.counters["steps_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  set_conv_implementation(ConvImplementation::kFused);
}
BENCHMARK(BM_TrainStep)
    ->Args({0, 0, 0})
    ->Args({0, 0, 1})
    ->Args({3, 0, 0})
    ->Args({2, 0, 0})
    ->Args({1, 0, 0})
    ->Args({1, 0, 1})
    ->Args({0, 1, 0})
    ->Args({3, 1, 0})
    ->Args({1, 1, 0})
    ->ArgNames({"impl", "hierarchy", "torch_adam"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Peak resident memory of training steps of the paper's architecture (Physion preset, C = 32,
// 4 levels) on 10k points. getrusage reports the process's high-water mark, so run this row on
// its own (--benchmark_filter=BM_TrainMemory) for a clean number.
void BM_TrainMemory(benchmark::State& state) {
  set_torch_threads(bench_threads());
  const PointState s = make_bench_state(10000);
  DynamicsModel model(config_for(0));
  model->train();
  torch::optim::Adam adam(model->parameters(), torch::optim::AdamOptions(1e-3));
  const ModelInput input = make_model_input(s, model->build_hierarchy(s));
  const torch::Tensor truth = input.position + 0.001;
  for (auto _ : state) {
    adam.zero_grad();
    const torch::Tensor err = (model->predict_positions(input) - truth).to(torch::kFloat);
    torch::nn::functional::huber_loss(err, torch::zeros_like(err)).backward();
    adam.step();
  }
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  state.counters["peak_rss_MiB"] = static_cast<double>(usage.ru_maxrss) / 1024.0;
}
BENCHMARK(BM_TrainMemory)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

}  // namespace
}  // namespace dynscope

BENCHMARK_MAIN();
