// Scene → RenderScene: meshes at their poses, point layers, level points, voxels and
// neighbourhoods.
#include "render/scene_adapter.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <tuple>

#include "engine/core/error.h"
#include "engine/geometry/grid_downsample.h"
#include "engine/geometry/interaction_points.h"
#include "engine/geometry/neighbors.h"
#include "engine/rollout/model_points.h"

namespace dynscope::render {
namespace {

const Color kPickedColor(0.95f, 0.10f, 0.55f);
const Color kObjectEdgeColor(0.10f, 0.35f, 0.85f);
const Color kRelationEdgeColor(1.00f, 0.50f, 0.00f);
const Color kInteractionColor(0.10f, 0.70f, 0.30f);
const Color kPredictionColor(0.95f, 0.45f, 0.10f);
const Color kDimmedColor(0.78f, 0.78f, 0.78f);

// Largest of 1, 2, 5 x 10^k not above `value`.
double round_spacing(double value) {
  const double decade = std::pow(10.0, std::floor(std::log10(value)));
  for (double m : {5.0, 2.0, 1.0}) {
    if (m * decade <= value) return m * decade;
  }
  return decade;
}

std::vector<float> categorical_colors(const std::vector<int32_t>& ids) {
  std::vector<float> colors;
  colors.reserve(ids.size() * 3);
  for (int32_t id : ids) {
    const Color c = categorical_color(id);
    colors.insert(colors.end(), {c.x(), c.y(), c.z()});
  }
  return colors;
}

std::shared_ptr<PointSeries> single_point(const Vec3& p) {
  Points one(1, 3);
  one.row(0) = p.transpose();
  return make_point_series({one});
}

std::shared_ptr<PointSeries> subset_series(const PointSeries& all,
                                           const std::vector<int32_t>& idx) {
  auto out = std::make_shared<PointSeries>();
  out->num_frames = all.num_frames;
  out->num_points = static_cast<int>(idx.size());
  out->positions.reserve(static_cast<size_t>(out->num_frames) * idx.size() * 3);
  for (int f = 0; f < all.num_frames; ++f) {
    for (int32_t i : idx) {
      const size_t k = (static_cast<size_t>(f) * all.num_points + i) * 3;
      out->positions.insert(out->positions.end(), all.positions.begin() + k,
                            all.positions.begin() + k + 3);
    }
  }
  if (!all.colors.empty()) {
    for (int32_t i : idx) {
      out->colors.insert(out->colors.end(), all.colors.begin() + 3 * i,
                         all.colors.begin() + 3 * i + 3);
    }
  }
  return out;
}

}  // namespace

GroundGrid grid_for_bounds(const Aabb& bounds) {
  GroundGrid grid;
  if (bounds.empty()) return grid;
  grid.height = bounds.min.z() < -1e-6 ? static_cast<float>(bounds.min.z()) : 0.0f;
  const Vec3 size = bounds.max - bounds.min;
  grid.center = Eigen::Vector2f(0.5f * static_cast<float>(bounds.min.x() + bounds.max.x()),
                                0.5f * static_cast<float>(bounds.min.y() + bounds.max.y()));
  const double half = std::max({0.5 * size.x(), 0.5 * size.y(), 0.5 * size.z(), 0.05});
  grid.extent = static_cast<float>(2.5 * half);
  grid.spacing = static_cast<float>(round_spacing(grid.extent / 6.0));
  return grid;
}

SceneRenderData::SceneRenderData(const Scene& scene, const ViewSpec& view) : scene_(scene) {
  scene_.validate();
  view.validate();
  level_ = view.level;
  voxel_ = view.voxel > 0 ? view.voxel : default_sampling_voxel(scene_.scenario);
  radius0_ = view.relation_radius > 0 ? view.relation_radius : 2.0 * voxel_;
  point_radius_ = view.point_radius > 0 ? view.point_radius : static_cast<float>(0.3 * voxel_);
  for (const Object& o : scene_.objects) {
    geometry_.push_back(o.rigid && !o.mesh.empty() ? make_mesh_geometry(o.mesh) : nullptr);
  }
  const ViewLayers& l = view.layers;
  const bool need_points =
      l.ground_truth || l.level_points || l.voxels || (l.neighborhoods && view.picked_point >= 0);
  if (!need_points || scene_.num_frames() == 0) return;
  PointCloudOptions options;
  options.voxel = voxel_;
  cloud_ = build_point_cloud(scene_, options);
  std::vector<Points> frames;
  frames.reserve(scene_.num_frames());
  for (int f = 0; f < scene_.num_frames(); ++f) frames.push_back(cloud_.positions(scene_, f));
  cloud_series_ = make_point_series(frames);
  cloud_series_->colors = categorical_colors(cloud_.object_id);
  if (level_ == 0) {
    level_indices_.resize(cloud_.size());
    for (Eigen::Index i = 0; i < cloud_.size(); ++i) level_indices_[i] = static_cast<int32_t>(i);
    level_series_ = cloud_series_;
  } else {
    // Downsampling in each object's rest frame keeps the level's points fixed over time.
    level_indices_ = grid_downsample_per_object(cloud_.rest, cloud_.object_id, level_voxel());
    level_series_ = subset_series(*cloud_series_, level_indices_);
  }
  for (int32_t i : level_indices_) level_object_.push_back(cloud_.object_id[i]);
}

double SceneRenderData::level_voxel() const { return voxel_ * std::pow(1.5, level_); }
double SceneRenderData::level_radius() const { return radius0_ * std::pow(1.5, level_); }
float SceneRenderData::point_radius() const { return point_radius_; }

Aabb SceneRenderData::bounds(int first, int last) const {
  Aabb box;
  const int frames = scene_.num_frames();
  for (int f = std::max(0, first); f <= std::min(last, frames - 1); ++f) {
    for (size_t i = 0; i < scene_.objects.size(); ++i) {
      box.extend(Aabb::of(scene_.world_vertices(static_cast<int>(i), f)));
    }
  }
  return box;
}

RenderScene SceneRenderData::frame(int frame, const ViewSpec& view) const {
  if (frame < 0 || frame >= num_frames()) {
    throw ValueError("frame", std::to_string(frame) + " is outside the scene's [0, " +
                                  std::to_string(num_frames()) + ")");
  }
  const ViewLayers& l = view.layers;
  RenderScene out;
  out.background = view.background;
  out.grid = grid_for_bounds(scene_.bounds());
  out.grid.visible = l.grid;
  const bool any_points = (l.ground_truth || l.level_points || l.interaction_points ||
                           (l.neighborhoods && view.picked_point >= 0));
  if (l.meshes) {
    for (size_t i = 0; i < scene_.objects.size(); ++i) {
      const Object& o = scene_.objects[i];
      MeshInstance m;
      m.name = o.name;
      m.color = o.color.cast<float>();
      // Points sit on the surfaces: meshes turn translucent so they do not hide them.
      m.opacity = any_points ? 0.3f : 1.0f;
      m.smooth = true;  // crease-angle normals: curved surfaces smooth, box edges stay sharp
      if (geometry_[i]) {
        m.geometry = geometry_[i];
        m.model = pose_matrix(scene_.trajectories[i].poses[frame], o.scale);
      } else {
        Mesh world;
        world.vertices = scene_.world_vertices(static_cast<int>(i), frame);
        world.faces = o.mesh.faces;
        if (world.empty()) continue;
        m.geometry = make_mesh_geometry(world);
      }
      out.meshes.push_back(std::move(m));
    }
  }
  // With a neighbourhood shown, the other points step back (small, grey) so it stands out.
  const bool dim = l.neighborhoods && view.picked_point >= 0;
  if (l.ground_truth && cloud_series_) {
    PointLayer layer;
    layer.name = "points";
    layer.series = cloud_series_;
    layer.frame = frame;
    layer.coloring = dim ? PointColoring::kUniform : PointColoring::kPerPoint;
    layer.color = kDimmedColor;
    layer.radius = dim ? 0.7f * point_radius_ : point_radius_;
    out.points.push_back(layer);
  }
  const float level_radius = point_radius_ * static_cast<float>(std::pow(1.5, level_));
  if (l.level_points && level_series_ && (level_ > 0 || !l.ground_truth)) {
    PointLayer layer;
    layer.name = "level " + std::to_string(level_);
    layer.series = level_series_;
    layer.frame = frame;
    layer.coloring = dim ? PointColoring::kUniform : PointColoring::kPerPoint;
    layer.color = kDimmedColor;
    layer.radius = dim ? 0.7f * level_radius : level_radius;
    out.points.push_back(layer);
  }
  if (l.voxels && level_series_) {
    const double v = level_voxel();
    std::set<std::tuple<int64_t, int64_t, int64_t, int32_t>> cells;
    for (int i = 0; i < level_series_->num_points; ++i) {
      const Vec3 p = level_series_->position(frame, i);
      cells.emplace(static_cast<int64_t>(std::floor(p.x() / v)),
                    static_cast<int64_t>(std::floor(p.y() / v)),
                    static_cast<int64_t>(std::floor(p.z() / v)), level_object_[i]);
    }
    for (const auto& [x, y, z, id] : cells) {
      WireBox box;
      box.min = Eigen::Vector3f(static_cast<float>(x * v), static_cast<float>(y * v),
                                static_cast<float>(z * v));
      box.max = box.min + Eigen::Vector3f::Constant(static_cast<float>(v));
      box.color = categorical_color(id) * 0.7f;
      out.boxes.push_back(box);
    }
  }
  if (l.neighborhoods && view.picked_point >= 0) add_neighborhoods(out, frame, view);
  if (l.interaction_points) add_interaction_points(out, frame);
  return out;
}

SceneRenderData::LevelNeighbors SceneRenderData::level_neighbors(int frame, int picked,
                                                                 int k) const {
  const int n = static_cast<int>(level_indices_.size());
  if (picked < 0 || picked >= n) {
    throw ValueError("picked_point", std::to_string(picked) + " is outside the " +
                                         std::to_string(n) + " points of level " +
                                         std::to_string(level_));
  }
  if (frame < 0 || frame >= num_frames()) {
    throw ValueError(
        "frame", std::to_string(frame) + " is outside [0, " + std::to_string(num_frames()) + ")");
  }
  if (k < 1) throw ValueError("neighbors", std::to_string(k) + " must be at least 1");
  LevelNeighbors out;
  // Exact (double) positions, not the float GPU series, so listed distances are exact.
  const Points all = cloud_.positions(scene_, frame);
  out.positions.resize(n, 3);
  for (int i = 0; i < n; ++i) out.positions.row(i) = all.row(level_indices_[i]);
  out.object = level_object_;
  const Points query = out.positions.row(picked);
  const std::vector<int32_t> query_id = {level_object_[picked]};
  out.same = knn_same_object(query, query_id, out.positions, level_object_, k);
  out.relational =
      knn_other_objects(query, query_id, out.positions, level_object_, k, level_radius());
  return out;
}

void SceneRenderData::add_neighborhoods(RenderScene& out, int frame, const ViewSpec& view) const {
  const int picked = view.picked_point;
  const LevelNeighbors nb = level_neighbors(frame, picked, view.neighbors);
  const Points& positions = nb.positions;
  const NeighborList& same = nb.same;
  const NeighborList& other = nb.relational;
  LineSet edges;
  edges.name = "neighbourhood";
  edges.width = 2.0f;
  const Vec3 center = positions.row(picked).transpose();
  std::vector<Vec3> same_list, other_list;
  for (Eigen::Index k = 0; k < same.k(); ++k) {
    const int32_t j = same.index(0, k);
    if (!same.mask(0, k) || j == picked) continue;
    edges.add(center, positions.row(j).transpose(), kObjectEdgeColor);
    same_list.push_back(positions.row(j).transpose());
  }
  for (Eigen::Index k = 0; k < other.k(); ++k) {
    if (!other.mask(0, k)) continue;
    const int32_t j = other.index(0, k);
    edges.add(center, positions.row(j).transpose(), kRelationEdgeColor);
    other_list.push_back(positions.row(j).transpose());
  }
  out.lines.push_back(std::move(edges));
  const float r = point_radius_ * static_cast<float>(std::pow(1.5, level_));
  auto add_points = [&](const std::vector<Vec3>& list, const Color& color, float radius,
                        const std::string& name) {
    if (list.empty()) return;
    Points p(static_cast<Eigen::Index>(list.size()), 3);
    for (size_t i = 0; i < list.size(); ++i) p.row(static_cast<Eigen::Index>(i)) = list[i];
    PointLayer layer;
    layer.name = name;
    layer.series = make_point_series({p});
    layer.coloring = PointColoring::kUniform;
    layer.color = color;
    layer.radius = radius;
    layer.pickable = false;
    out.points.push_back(layer);
  };
  add_points(same_list, kObjectEdgeColor, 1.25f * r, "object neighbours");
  add_points(other_list, kRelationEdgeColor, 1.25f * r, "relational neighbours");
  PointLayer highlight;
  highlight.name = "picked point";
  highlight.series = single_point(center);
  highlight.color = kPickedColor;
  highlight.radius = 1.8f * r;
  highlight.pickable = false;
  out.points.push_back(highlight);
}

void SceneRenderData::add_interaction_points(RenderScene& out, int frame) const {
  Points vertices(0, 3);
  Faces faces(0, 3);
  std::vector<int32_t> face_object;
  for (size_t i = 0; i < scene_.objects.size(); ++i) {
    const Points v = scene_.world_vertices(static_cast<int>(i), frame);
    const Faces& f = scene_.objects[i].mesh.faces;
    const Eigen::Index v0 = vertices.rows(), f0 = faces.rows();
    vertices.conservativeResize(v0 + v.rows(), 3);
    vertices.bottomRows(v.rows()) = v;
    faces.conservativeResize(f0 + f.rows(), 3);
    faces.bottomRows(f.rows()) = (f.array() + static_cast<int32_t>(v0)).matrix();
    face_object.insert(face_object.end(), f.rows(), scene_.objects[i].id);
  }
  const InteractionPoints ip = find_interaction_points(vertices, faces, face_object, radius0_, 2);
  if (ip.size() == 0) return;
  LineSet pairs;
  pairs.name = "interaction points";
  pairs.color = kInteractionColor;
  pairs.width = 2.0f;
  Points ends(static_cast<Eigen::Index>(2 * ip.size()), 3);
  for (size_t p = 0; p < ip.size(); ++p) {
    pairs.add(ip.point_a.row(p).transpose(), ip.point_b.row(p).transpose(), kInteractionColor);
    ends.row(static_cast<Eigen::Index>(2 * p)) = ip.point_a.row(p);
    ends.row(static_cast<Eigen::Index>(2 * p + 1)) = ip.point_b.row(p);
  }
  out.lines.push_back(std::move(pairs));
  PointLayer layer;
  layer.name = "interaction points";
  layer.series = make_point_series({ends});
  layer.color = kInteractionColor;
  layer.radius = 0.6f * point_radius_;
  layer.pickable = false;
  out.points.push_back(layer);
}

std::vector<std::string> SceneRenderData::legend(const ViewSpec& view) const {
  const ViewLayers& l = view.layers;
  std::vector<std::string> lines;
  if (l.ground_truth) lines.push_back("points: " + std::to_string(cloud_.size()));
  if (l.level_points || l.voxels) {
    char text[96];
    std::snprintf(text, sizeof(text), "level %d: %zu points, voxel %.3g", level_,
                  level_indices_.size(), level_voxel());
    lines.push_back(text);
  }
  if (l.neighborhoods && view.picked_point >= 0) {
    char text[128];
    std::snprintf(text, sizeof(text), "point %d: knn %d (blue), r %.3g (orange)", view.picked_point,
                  view.neighbors, level_radius());
    lines.push_back(text);
  }
  if (l.interaction_points) lines.push_back("interaction points (green)");
  return lines;
}

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
    PointLayer p = layer("prediction", series.prediction);
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

}  // namespace dynscope::render
