// Viewer frame time while scrubbing a rollout headless (OSMesa, null platform, whole UI drawn):
// 10k and 100k points, 24 frames, ghost mode with error colours, one frame step per iteration.
// Counters: ui_cpu_ms is the UI thread's CPU time per frame (CLOCK_THREAD_CPUTIME_ID: panels,
// viewports, validation and the GL calls made on that thread; llvmpipe's rasteriser threads are
// not counted), prepare_cpu_ms the part before any GL call (state, panels, RenderScenes).
#include <benchmark/benchmark.h>
#include <imgui.h>
#include <time.h>

#include <cstdio>
#include <memory>
#include <string>

#include "app/viewer/null_platform.h"
#include "app/viewer/viewer_app.h"
#include "engine/core/rng.h"
#include "render/context_factory.h"
#include "render/gl_functions.h"

namespace dynscope::app::viewer {
namespace {

constexpr int kWidth = 1280;
constexpr int kHeight = 720;
constexpr int kFrames = 24;

render::GlContext& context() {
  static std::unique_ptr<render::GlContext> c = render::create_context("osmesa", kWidth, kHeight);
  c->make_current();
  return *c;
}

// Ten drifting objects of n/10 points each; the prediction drifts away from the truth.
Rollout synthetic_rollout(int n) {
  Rng rng(7);
  Rollout r;
  r.scenario = "movi-a";
  r.dt_s = 1.0 / 12.0;
  r.observed_frames = 3;
  r.sampling_voxel = 0.05;
  const int objects = 10;
  r.rest.resize(n, 3);
  r.object_ids.resize(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    r.object_ids[static_cast<size_t>(i)] = i % objects;
    r.rest.row(i) =
        Vec3(rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5)).transpose();
  }
  for (int o = 0; o < objects; ++o) {
    r.pose_object_ids.push_back(o);
    r.pose_rigid.push_back(1);
  }
  for (int f = 0; f < kFrames; ++f) {
    Points truth(n, 3), pred(n, 3);
    std::vector<Pose> poses(static_cast<size_t>(objects));
    for (int o = 0; o < objects; ++o) {
      poses[static_cast<size_t>(o)].position = Vec3(1.5 * (o % 5) + 0.1 * f, 1.5 * (o / 5), 1.0);
    }
    for (int i = 0; i < n; ++i) {
      const Pose& p = poses[static_cast<size_t>(i % objects)];
      truth.row(i) = p.apply(Vec3(r.rest.row(i).transpose())).transpose();
      pred.row(i) = truth.row(i) + Eigen::RowVector3d(0.01 * f, 0.0, 0.0);
    }
    r.truth.push_back(truth);
    r.predicted.push_back(pred);
    r.poses.push_back(poses);
    r.point_error.push_back(0.01 * f);
  }
  return r;
}

double thread_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
}

// args: points, point style (0 auto, 1 spheres, 2 discs).
void BM_ScrubRollout(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const char* styles[] = {"auto", "spheres", "discs"};
  const Rollout rollout = synthetic_rollout(n);
  ImGuiSession session;
  NullPlatform platform(kWidth, kHeight);
  ViewerApp app(context(), platform);
  app.state().set_rollout(rollout, "synthetic", nullptr);
  app.state().set_point_style(styles[state.range(1)]);
  for (int i = 0; i < 3; ++i) app.frame();  // layout and first upload
  int frame = 0;
  double ui_ms = 0.0, prepare_ms = 0.0;
  for (auto _ : state) {
    frame = (frame + 1) % kFrames;
    const double t0 = thread_cpu_ms();
    app.state().set_frame(frame);
    // What a frame computes before GL: the state's RenderScenes (panels are measured in ui_cpu_ms).
    benchmark::DoNotOptimize(app.viewports());
    const double t1 = thread_cpu_ms();
    app.frame();
    const double t2 = thread_cpu_ms();
    prepare_ms += t1 - t0;
    ui_ms += t2 - t1;
  }
  const double iterations = static_cast<double>(state.iterations());
  state.counters["points"] = n;
  state.counters["ui_cpu_ms"] = ui_ms / iterations;
  state.counters["prepare_cpu_ms"] = prepare_ms / iterations;
  state.counters["fps"] = benchmark::Counter(iterations, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_ScrubRollout)
    ->ArgNames({"points", "style"})
    ->Args({10000, 0})
    ->Args({100000, 0})
    ->Args({100000, 1})
    ->Args({100000, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace dynscope::app::viewer

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  // The machine the numbers come from (a speed claim is a ratio measured in one run).
  dynscope::render::GlFunctions gl;
  gl.load(dynscope::app::viewer::context());
  std::printf("GL: %s\n", gl.describe().c_str());
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
