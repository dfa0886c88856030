// RolloutDocument: series, meshes and per-frame RenderScenes of a rollout shown in the viewer.
#include "app/viewer/rollout_document.h"

#include <algorithm>

#include "engine/core/error.h"

namespace dynscope::app::viewer {
namespace {

void check_frame(const RolloutDocument& doc, int frame) {
  if (frame < 0 || frame >= doc.num_frames()) {
    throw ValueError("frame", std::to_string(frame) + " is outside the rollout's " +
                                  std::to_string(doc.num_frames()) + " frames (" + doc.path + ")");
  }
}

}  // namespace

const char* rollout_mode_name(RolloutMode mode) {
  switch (mode) {
    case RolloutMode::kPrediction:
      return "prediction";
    case RolloutMode::kTruth:
      return "truth";
    case RolloutMode::kGhost:
      return "ghost";
    case RolloutMode::kSideBySide:
      return "side by side";
  }
  return "prediction";
}

std::unique_ptr<RolloutDocument> make_rollout_document(Rollout rollout, const std::string& path,
                                                       const Scene* scene) {
  auto doc = std::make_unique<RolloutDocument>();
  try {
    static_cast<render::RolloutRenderData&>(*doc) =
        render::make_rollout_render_data(std::move(rollout), scene);
  } catch (const ValueError& e) {
    throw ValueError("rollout", path + ": " + e.what());
  }
  doc->path = path;
  return doc;
}

void add_prediction_ghost(render::RenderScene& out, const RolloutDocument& other, int frame) {
  check_frame(other, frame);
  render::PointLayer ghost;
  ghost.name = "compared prediction (ghost)";
  ghost.series = other.series.prediction;
  ghost.frame = frame;
  ghost.radius = other.point_radius;
  ghost.coloring = render::PointColoring::kPerPoint;
  ghost.opacity = 0.3f;
  ghost.pickable = false;
  out.points.push_back(std::move(ghost));
}

int first_frame_over(const std::vector<double>& values, double threshold) {
  const auto it =
      std::find_if(values.begin(), values.end(), [&](double v) { return v > threshold; });
  return it == values.end() ? -1 : static_cast<int>(it - values.begin());
}

}  // namespace dynscope::app::viewer
