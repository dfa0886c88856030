// Viewer frame time while scrubbing a rollout headless (OSMesa, null platform, whole UI drawn):
// 10k and 100k points, 24 frames, ghost mode with error colours, one frame step per iteration.
// Counters (per frame, CPU of the UI thread, CLOCK_THREAD_CPUTIME_ID; llvmpipe's rasteriser
// threads are not counted): ui_cpu_ms all of it; app_cpu_ms the viewer's own work (input, state,
// panels, ImGui, viewports: everything outside the renderers); gl_cpu_ms the part inside the
// renderers' GL calls, where llvmpipe runs the vertex stage on the calling thread (a GPU driver
// does not); uploads_per_frame buffer uploads while scrubbing (0: nothing is re-sent). Rows with
// view_thread:1 draw the 3D view on ViewerApp's view thread (its own OSMesa context): the UI
// thread then only hands the view over and shows the newest finished image, and view_fps counts
// the images the view thread finished per second while the UI ran.
#include <benchmark/benchmark.h>
#include <imgui.h>

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

// args: points, point style (0 auto, 1 spheres, 2 discs), view thread (0 off, 1 on).
void BM_ScrubRollout(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const char* styles[] = {"auto", "spheres", "discs"};
  const Rollout rollout = synthetic_rollout(n);
  ImGuiSession session;
  NullPlatform platform(kWidth, kHeight);
  ViewerApp app(context(), platform);
  app.state().set_rollout(rollout, "synthetic", nullptr);
  app.state().set_point_style(styles[state.range(1)]);
  app.set_view_thread(state.range(2) != 0);
  for (int i = 0; i < 3; ++i) {  // layout and first upload
    app.frame();
    app.wait_for_view();
  }
  const int64_t images = app.view_images();
  int frame = 0;
  double ui_ms = 0.0, gl_ms = 0.0;
  const int64_t uploads = app.upload_count();
  for (auto _ : state) {
    frame = (frame + 1) % kFrames;
    app.state().set_frame(frame);
    app.frame();
    ui_ms += app.frame_cpu().total_ms;
    gl_ms += app.frame_cpu().gl_ms;
  }
  const double iterations = static_cast<double>(state.iterations());
  state.counters["points"] = n;
  state.counters["ui_cpu_ms"] = ui_ms / iterations;
  state.counters["app_cpu_ms"] = (ui_ms - gl_ms) / iterations;
  state.counters["gl_cpu_ms"] = gl_ms / iterations;
  state.counters["uploads_per_frame"] =
      static_cast<double>(app.upload_count() - uploads) / iterations;
  state.counters["fps"] = benchmark::Counter(iterations, benchmark::Counter::kIsRate);
  if (app.view_thread()) {
    // Views the thread finished while the UI ran its frames (each shows the newest one).
    state.counters["view_fps"] = benchmark::Counter(static_cast<double>(app.view_images() - images),
                                                    benchmark::Counter::kIsRate);
  }
}
BENCHMARK(BM_ScrubRollout)
    ->ArgNames({"points", "style", "view_thread"})
    ->Args({10000, 0, 0})
    ->Args({100000, 0, 0})
    ->Args({100000, 1, 0})
    ->Args({100000, 2, 0})
    ->Args({10000, 0, 1})
    ->Args({100000, 0, 1})
    ->Args({100000, 1, 1})
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
