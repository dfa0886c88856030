// Viewer frame time while scrubbing a rollout headless (OSMesa, null platform, whole UI drawn):
// 10k and 100k points, 24 frames, ghost mode with error colours, one frame step per iteration.
#include <benchmark/benchmark.h>

#include <memory>

#include "app/viewer/null_platform.h"
#include "app/viewer/viewer_app.h"
#include "engine/core/rng.h"
#include "render/context_factory.h"

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
    r.rest.row(i) = Vec3(rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5))
                        .transpose();
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

void BM_ScrubRollout(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const Rollout rollout = synthetic_rollout(n);
  ImGuiSession session;
  NullPlatform platform(kWidth, kHeight);
  ViewerApp app(context(), platform);
  app.set_rollout(rollout, "synthetic", nullptr);
  for (int i = 0; i < 3; ++i) app.frame();  // layout and first upload
  int frame = 0;
  for (auto _ : state) {
    frame = (frame + 1) % kFrames;
    app.set_frame(frame);
    app.frame();
  }
  state.counters["points"] = n;
  state.counters["fps"] = benchmark::Counter(static_cast<double>(state.iterations()),
                                             benchmark::Counter::kIsRate);
}
BENCHMARK(BM_ScrubRollout)->Arg(10000)->Arg(100000)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace dynscope::app::viewer

BENCHMARK_MAIN();
