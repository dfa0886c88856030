// Golden-image tests (320x240, OSMesa): compare with tests/render/golden/*.png within a small
// per-pixel tolerance; DYNSCOPE_UPDATE_GOLDEN=1 rewrites the goldens (see README.md).
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>

#include "render/batch_render.h"
#include "render/png_io.h"
#include "render/renderer.h"
#include "render/scene_adapter.h"
#include "render_test_util.h"

namespace dynscope::render {
namespace {

namespace fs = std::filesystem;

constexpr int kWidth = 320;
constexpr int kHeight = 240;
constexpr int kTolerance = 8;           // max channel difference of a matching pixel
constexpr double kMinFraction = 0.995;  // share of pixels that must match

void expect_matches_golden(const Image& actual, const std::string& name) {
  const fs::path golden = fs::path(DYNSCOPE_SOURCE_DIR) / "tests/render/golden" / (name + ".png");
  const char* update = std::getenv("DYNSCOPE_UPDATE_GOLDEN");
  if (update && std::string(update) == "1") {
    write_png(golden.string(), actual);
    std::printf("updated %s\n", golden.c_str());
    return;
  }
  ASSERT_TRUE(fs::exists(golden)) << golden << " is missing; run tests/render/update_goldens.sh";
  const Image expected = read_png(golden.string());
  const ImageComparison c = compare_images(actual, expected, kTolerance);
  if (c.fraction_within < kMinFraction) {
    const fs::path dir = DYNSCOPE_RENDER_ARTIFACT_DIR;
    fs::create_directories(dir);
    const fs::path actual_path = dir / (name + "_actual.png");
    const fs::path diff_path = dir / (name + "_diff.png");
    write_png(actual_path.string(), actual);
    write_png(diff_path.string(), c.diff);
    ADD_FAILURE() << name << ": only " << 100.0 * c.fraction_within << "% of pixels within "
                  << kTolerance << " (max difference " << c.max_difference
                  << ")\n  golden: " << golden.string() << "\n  actual: " << actual_path.string()
                  << "\n  diff:   " << diff_path.string();
  }
}

Image render_view(const RenderScene& scene, const Camera& camera) {
  GlContext& context = testing::osmesa(kWidth, kHeight);
  Renderer renderer(context, 4);
  return renderer.render_image(scene, camera);
}

TEST(Golden, SceneFrame) {
  const Scene scene = testing::shapes_scene(1);
  ViewSpec view;
  SceneRenderData data(scene, view);
  Camera camera;
  camera.fit(data.bounds(0, 0), static_cast<double>(kWidth) / kHeight);
  expect_matches_golden(render_view(data.frame(0, view), camera), "scene_frame");
}

TEST(Golden, PredictionVersusTruthError) {
  // Two point clouds on spheres; the prediction drifts along +x with height, so the error grows
  // from bottom to top of each object.
  std::vector<Points> truth, pred;
  std::vector<int32_t> ids;
  Points t(0, 3);
  for (int object = 0; object < 2; ++object) {
    const Vec3 centre(object == 0 ? -0.6 : 0.6, 0.0, 0.5);
    for (int i = 0; i < 20; ++i) {
      for (int j = 0; j < 20; ++j) {
        const double theta = M_PI * (i + 0.5) / 20, phi = 2 * M_PI * j / 20;
        t.conservativeResize(t.rows() + 1, 3);
        t.row(t.rows() - 1) =
            (centre + 0.45 * Vec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                                  std::cos(theta)))
                .transpose();
        ids.push_back(object);
      }
    }
  }
  Points p = t;
  for (Eigen::Index i = 0; i < p.rows(); ++i) p(i, 0) += 0.15 * t(i, 2) * t(i, 2);
  const ComparisonSeries series = make_comparison_series({t}, {p}, ids);
  ViewSpec view;
  view.layers.error = true;
  view.layers.ghost = true;
  view.colormap = "turbo";
  RenderScene scene;
  scene.grid = grid_for_bounds(series.truth->bounds(0));
  add_comparison_layers(scene, series, 0, view, 0.035f);
  Camera camera;
  camera.fit(scene.bounds(), static_cast<double>(kWidth) / kHeight);
  expect_matches_golden(render_view(scene, camera), "prediction_error");
}

TEST(Golden, NeighbourhoodOverlay) {
  Scene scene;
  scene.scenario = "drop";
  testing::add_object(scene, 0, "left", make_box_mesh(Vec3(0.3, 0.3, 0.3)), Vec3(-0.17, 0, 0.15),
                      Vec3(0.8, 0.3, 0.3));
  testing::add_object(scene, 1, "right", make_box_mesh(Vec3(0.3, 0.3, 0.3)), Vec3(0.17, 0, 0.15),
                      Vec3(0.3, 0.5, 0.8));
  ViewSpec view;
  view.layers.ground_truth = true;
  view.layers.neighborhoods = true;
  SceneRenderData probe(scene, view);
  // Pick the left box's point on its top edge next to the gap: visible from above, and close
  // enough to the right box for relational edges.
  const Points pos = probe.cloud().positions(scene, 0);
  int picked = -1;
  double best = -1e9;
  for (Eigen::Index i = 0; i < pos.rows(); ++i) {
    const double score = 2.0 * pos(i, 2) + pos(i, 0) - std::abs(pos(i, 1));
    if (probe.cloud().object_id[i] == 0 && score > best) {
      best = score;
      picked = static_cast<int>(i);
    }
  }
  view.picked_point = picked;
  // The model's own lists at frame 0 (Physion preset: K = 16, relational radius 0.1).
  SceneRenderData data(scene, view, make_level_views(scene, view)->at(0));
  Camera camera;
  camera.set_preset(ViewPreset::kIso);
  camera.fit(data.bounds(0, 0), static_cast<double>(kWidth) / kHeight, 0.9);
  const RenderScene frame = data.frame(0, view);
  ASSERT_EQ(frame.lines.size(), 1u);
  expect_matches_golden(render_view(frame, camera), "neighbourhood");
}

}  // namespace
}  // namespace dynscope::render
