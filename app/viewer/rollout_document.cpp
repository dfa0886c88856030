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
  rollout.validate();
  if (rollout.num_frames() == 0) throw ValueError("rollout", path + " has no frames");
  auto doc = std::make_unique<RolloutDocument>();
  doc->path = path;
  doc->series =
      render::make_comparison_series(rollout.truth, rollout.predicted, rollout.object_ids);
  for (int f = 0; f < rollout.num_frames(); ++f) {
    doc->bounds.extend(doc->series.truth->bounds(f));
    doc->bounds.extend(doc->series.prediction->bounds(f));
  }
  doc->grid = render::grid_for_bounds(doc->bounds);
  // As `dynscope render`: a third of the sampling voxel, else 1% of the extent.
  const double extent = doc->bounds.empty() ? 1.0 : (doc->bounds.max - doc->bounds.min).norm();
  doc->point_radius = static_cast<float>(
      rollout.sampling_voxel > 0 ? 0.3 * rollout.sampling_voxel : 0.01 * std::max(extent, 1e-3));
  doc->geometry.resize(static_cast<size_t>(rollout.num_objects()));
  if (scene != nullptr && scene->num_frames() >= rollout.num_frames()) {
    doc->scene = *scene;
    for (int i = 0; i < rollout.num_objects(); ++i) {
      const int index = scene->object_index(rollout.pose_object_ids[static_cast<size_t>(i)]);
      if (index < 0 || rollout.pose_rigid[static_cast<size_t>(i)] == 0 ||
          scene->objects[static_cast<size_t>(index)].mesh.empty()) {
        continue;
      }
      doc->geometry[static_cast<size_t>(i)] =
          render::make_mesh_geometry(scene->objects[static_cast<size_t>(index)].mesh);
    }
  }
  doc->rollout = std::move(rollout);
  return doc;
}

render::RenderScene rollout_frame(const RolloutDocument& doc, int frame,
                                  const render::ViewSpec& view) {
  check_frame(doc, frame);
  render::RenderScene out;
  out.background = view.background;
  out.grid = doc.grid;
  out.grid.visible = view.layers.grid;
  if (view.layers.meshes && doc.scene) {
    const Rollout& r = doc.rollout;
    for (int i = 0; i < r.num_objects(); ++i) {
      if (!doc.geometry[static_cast<size_t>(i)]) continue;
      const int index = doc.scene->object_index(r.pose_object_ids[static_cast<size_t>(i)]);
      const Object& o = doc.scene->objects[static_cast<size_t>(index)];
      render::MeshInstance m;
      m.name = o.name;
      m.geometry = doc.geometry[static_cast<size_t>(i)];
      m.color = o.color.cast<float>();
      m.opacity = 0.3f;  // the points on the surface stay visible
      m.smooth = true;
      const Pose& pose = view.layers.prediction
                             ? r.poses[static_cast<size_t>(frame)][static_cast<size_t>(i)]
                             : doc.scene->trajectories[static_cast<size_t>(index)]
                                   .poses[static_cast<size_t>(frame)];
      m.model = render::pose_matrix(pose, o.scale);  // rest coordinates carry the scale
      out.meshes.push_back(std::move(m));
    }
  }
  render::add_comparison_layers(out, doc.series, frame, view, doc.point_radius);
  return out;
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
