// Renderer throughput on OSMesa at 1280x720: 10k / 100k / 1M points as sphere impostors or flat
// discs, with and without meshes.
#include <benchmark/benchmark.h>

#include "engine/core/rng.h"
#include "engine/scene/mesh.h"
#include "render/context_factory.h"
#include "render/renderer.h"

namespace dynscope::render {
namespace {

GlContext& context() {
  static std::unique_ptr<GlContext> c = create_context("osmesa", 1280, 720);
  c->make_current();
  return *c;
}

// args: number of points, mesh layer (0/1), multisampling samples, style (1 spheres, 2 discs).
void BM_RenderFrame(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const bool meshes = state.range(1) != 0;
  const PointStyle style = state.range(3) == 2 ? PointStyle::kDiscs : PointStyle::kSpheres;
  Renderer renderer(context(), static_cast<int>(state.range(2)));
  Rng rng(1);
  // Ten frames of a drifting cloud: the loop scrubs through them like the viewer does.
  std::vector<Points> frames(10, Points(n, 3));
  for (int i = 0; i < n; ++i) {
    const Vec3 p(rng.uniform(-2, 2), rng.uniform(-2, 2), rng.uniform(0, 2));
    for (int f = 0; f < 10; ++f) frames[f].row(i) = (p + Vec3(0.02 * f, 0, 0)).transpose();
  }
  auto series = make_point_series(frames);
  RenderScene scene;
  scene.point_style = style;
  PointLayer layer;
  layer.series = series;
  layer.radius = n > 50000 ? 0.01f : 0.02f;
  layer.color = Color(0.2f, 0.5f, 0.9f);
  scene.points.push_back(layer);
  if (meshes) {
    auto sphere = make_mesh_geometry(make_sphere_mesh(0.5, 24, 48));
    auto box = make_mesh_geometry(make_box_mesh(Vec3(0.8, 0.8, 0.8)));
    for (int k = 0; k < 8; ++k) {
      MeshInstance m;
      m.geometry = k % 2 ? sphere : box;
      m.model = pose_matrix(Pose{Vec3(-1.5 + 0.45 * k, 0.5 * (k % 3), 0.5), Quat::Identity()});
      m.color = categorical_color(k);
      m.smooth = true;
      scene.meshes.push_back(m);
    }
  }
  Camera camera;
  camera.fit(scene.bounds(), 1280.0 / 720.0);
  int f = 0;
  for (auto _ : state) {
    scene.points[0].frame = f++ % 10;
    renderer.render(scene, camera);
    renderer.gl().Finish();
  }
  state.counters["fps"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_RenderFrame)
    ->ArgNames({"points", "meshes", "samples", "style"})
    ->Args({10000, 0, 0, 1})
    ->Args({10000, 1, 0, 1})
    ->Args({100000, 0, 0, 1})
    ->Args({100000, 1, 0, 1})
    ->Args({10000, 1, 4, 1})
    ->Args({100000, 1, 4, 1})
    ->Args({100000, 0, 0, 2})
    ->Args({100000, 1, 0, 2})
    ->Args({100000, 1, 4, 2})
    ->Args({1000000, 0, 0, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace dynscope::render

BENCHMARK_MAIN();
