// Rollout → RenderScene: the truth/prediction series built once, their point layers, and the
// meshes at the fitted poses (declared in scene_adapter.h).
#include <algorithm>
#include <cmath>

#include "engine/core/error.h"
#include "render/colormap.h"
#include "render/scene_adapter.h"

namespace dynscope::render {
namespace {

const Color kPredictionColor(0.95f, 0.45f, 0.10f);
// Attribution shares below this fraction of the largest are drawn as "no share" (grey).
constexpr float kNegligibleShare = 0.01f;

}  // namespace

ComparisonSeries make_comparison_series(const std::vector<Points>& truth,
                                        const std::vector<Points>& predicted,
                                        const std::vector<int32_t>& object_ids) {
  if (truth.size() != predicted.size()) {
    throw ValueError("rollout", "truth has " + std::to_string(truth.size()) +
                                    " frames, prediction " + std::to_string(predicted.size()));
  }
  for (size_t f = 0; f < truth.size(); ++f) {
    if (truth[f].rows() != predicted[f].rows()) {
      throw ValueError("rollout", "frame " + std::to_string(f) + ": truth has " +
                                      std::to_string(truth[f].rows()) + " points, prediction " +
                                      std::to_string(predicted[f].rows()));
    }
  }
  ComparisonSeries out;
  out.truth = make_point_series(truth);
  out.prediction = make_point_series(predicted);
  if (static_cast<int>(object_ids.size()) != out.truth->num_points) {
    throw ValueError("rollout object ids", std::to_string(object_ids.size()) + " ids for " +
                                               std::to_string(out.truth->num_points) + " points");
  }
  out.truth->colors = categorical_colors(object_ids);
  out.prediction->colors = out.truth->colors;
  out.prediction->scalars.reserve(static_cast<size_t>(out.truth->num_frames) *
                                  out.truth->num_points);
  for (size_t f = 0; f < truth.size(); ++f) {
    for (Eigen::Index i = 0; i < truth[f].rows(); ++i) {
      const float e = static_cast<float>((predicted[f].row(i) - truth[f].row(i)).norm());
      out.prediction->scalars.push_back(e);
      out.max_error = std::max(out.max_error, e);
    }
  }
  return out;
}

void add_comparison_layers(RenderScene& out, const ComparisonSeries& series, int frame,
                           const ViewSpec& view, float radius) {
  const ViewLayers& l = view.layers;
  auto layer = [&](const std::string& name, const std::shared_ptr<PointSeries>& s) {
    PointLayer p;
    p.name = name;
    p.series = s;
    p.frame = frame;
    p.radius = radius;
    p.coloring = PointColoring::kPerPoint;
    return p;
  };
  if (l.ground_truth) out.points.push_back(layer("truth", series.truth));
  if (l.prediction) {
    PointLayer p = layer(kPredictionLayer, series.prediction);
    if (l.error) {
      p.coloring = PointColoring::kScalar;
      p.colormap = view.colormap;
      p.range_min = view.auto_range ? 0.0f : view.range_min;
      p.range_max = view.auto_range ? std::max(series.max_error, 1e-6f) : view.range_max;
    } else if (l.ground_truth) {
      // Both sets opaque: give the prediction one colour so the two can be told apart.
      p.coloring = PointColoring::kUniform;
      p.color = kPredictionColor;
    }
    out.points.push_back(p);
  }
  if (l.ghost && l.prediction != l.ground_truth) {
    PointLayer ghost = layer(l.prediction ? "truth (ghost)" : "prediction (ghost)",
                             l.prediction ? series.truth : series.prediction);
    ghost.opacity = 0.3f;
    ghost.pickable = false;
    out.points.push_back(ghost);
  }
}

std::shared_ptr<PointSeries> make_attribution_series(const RolloutRenderData& data,
                                                     const PointAttribution& attribution) {
  const PointSeries& prediction = *data.series.prediction;
  const auto n = static_cast<size_t>(prediction.num_points);
  if (attribution.shares.size() != n) {
    throw ValueError("attribution", std::to_string(attribution.shares.size()) + " shares for " +
                                        std::to_string(n) + " rollout points");
  }
  for (int i : attribution.explained) {
    if (i < 0 || static_cast<size_t>(i) >= n) {
      throw ValueError("attribution",
                       "explained point " + std::to_string(i) + " is not a rollout point");
    }
  }
  float largest = 0.0f;
  for (float v : attribution.shares) {
    if (!std::isfinite(v) || v < 0) throw ValueError("attribution", "shares must be >= 0");
    largest = std::max(largest, v);
  }
  auto s = std::make_shared<PointSeries>();
  s->num_frames = prediction.num_frames;
  s->num_points = prediction.num_points;
  s->positions = prediction.positions;
  s->colors.reserve(3 * n);
  const Color none(0.80f, 0.80f, 0.80f);
  for (float v : attribution.shares) {
    const float t = largest > 0 ? v / largest : 0.0f;
    const Color c = t >= kNegligibleShare ? colormap("turbo", 0.1f + 0.9f * std::sqrt(t)) : none;
    s->colors.insert(s->colors.end(), {c.x(), c.y(), c.z()});
  }
  return s;
}

void add_attribution_layers(RenderScene& out, const std::shared_ptr<PointSeries>& series,
                            const PointAttribution& attribution, int frame, float radius) {
  PointLayer layer;
  layer.name = "attribution";
  layer.series = series;
  layer.frame = frame;
  layer.radius = radius;
  layer.coloring = PointColoring::kPerPoint;
  const auto it = std::find_if(out.points.begin(), out.points.end(),
                               [](const PointLayer& p) { return p.name == kPredictionLayer; });
  if (it != out.points.end()) {
    *it = layer;
  } else {
    out.points.push_back(layer);
  }
  if (attribution.explained.empty()) return;
  std::vector<Points> halo(1, Points(static_cast<Eigen::Index>(attribution.explained.size()), 3));
  for (size_t i = 0; i < attribution.explained.size(); ++i) {
    halo[0].row(static_cast<Eigen::Index>(i)) =
        series->position(frame, attribution.explained[i]).transpose();
  }
  PointLayer h;
  h.name = "explained";
  h.series = make_point_series(halo);
  h.frame = 0;
  h.radius = 1.6f * radius;
  h.color = Color(0.10f, 0.75f, 0.95f);
  h.opacity = 0.25f;
  h.pickable = false;
  out.points.push_back(h);
}

RolloutRenderData make_rollout_render_data(Rollout rollout, const Scene* scene,
                                           float point_radius) {
  rollout.validate();
  if (rollout.num_frames() == 0) throw ValueError("rollout", "the rollout has no frames");
  RolloutRenderData d;
  d.series = make_comparison_series(rollout.truth, rollout.predicted, rollout.object_ids);
  for (int f = 0; f < rollout.num_frames(); ++f) {
    d.bounds.extend(d.series.truth->bounds(f));
    d.bounds.extend(d.series.prediction->bounds(f));
  }
  d.grid = grid_for_bounds(d.bounds);
  // Points a third of the sampling voxel apart would overlap; without a voxel, scale by extent.
  const double extent = d.bounds.empty() ? 1.0 : (d.bounds.max - d.bounds.min).norm();
  d.point_radius = point_radius > 0.0f ? point_radius
                                       : static_cast<float>(rollout.sampling_voxel > 0
                                                                ? 0.3 * rollout.sampling_voxel
                                                                : 0.01 * std::max(extent, 1e-3));
  d.geometry.resize(static_cast<size_t>(rollout.num_objects()));
  if (scene != nullptr && scene->num_frames() >= rollout.num_frames()) {
    d.scene = *scene;
    for (int i = 0; i < rollout.num_objects(); ++i) {
      const int index = scene->object_index(rollout.pose_object_ids[static_cast<size_t>(i)]);
      if (index < 0 || rollout.pose_rigid[static_cast<size_t>(i)] == 0 ||
          scene->objects[static_cast<size_t>(index)].mesh.empty()) {
        continue;
      }
      d.geometry[static_cast<size_t>(i)] =
          make_mesh_geometry(scene->objects[static_cast<size_t>(index)].mesh);
    }
  }
  d.rollout = std::move(rollout);
  return d;
}

RenderScene rollout_frame(const RolloutRenderData& data, int frame, const ViewSpec& view) {
  if (frame < 0 || frame >= data.num_frames()) {
    throw ValueError("frame", std::to_string(frame) + " is outside the rollout's " +
                                  std::to_string(data.num_frames()) + " frames");
  }
  RenderScene out;
  out.background = view.background;
  out.point_style = parse_point_style(view.point_style);
  out.grid = data.grid;
  out.grid.visible = view.layers.grid;
  if (view.layers.meshes && data.scene) {
    const Rollout& r = data.rollout;
    for (int i = 0; i < r.num_objects(); ++i) {
      if (!data.geometry[static_cast<size_t>(i)]) continue;
      const int index = data.scene->object_index(r.pose_object_ids[static_cast<size_t>(i)]);
      const Object& o = data.scene->objects[static_cast<size_t>(index)];
      MeshInstance m;
      m.name = o.name;
      m.geometry = data.geometry[static_cast<size_t>(i)];
      m.color = o.color.cast<float>();
      m.opacity = 0.3f;  // the points on the surface stay visible
      m.smooth = true;
      const Pose& pose = view.layers.prediction
                             ? r.poses[static_cast<size_t>(frame)][static_cast<size_t>(i)]
                             : data.scene->trajectories[static_cast<size_t>(index)]
                                   .poses[static_cast<size_t>(frame)];
      m.model = pose_matrix(pose, o.scale);  // rest coordinates carry the scale
      out.meshes.push_back(std::move(m));
    }
  }
  add_comparison_layers(out, data.series, frame, view, data.point_radius);
  return out;
}

}  // namespace dynscope::render
