// Scene → RenderScene: meshes at their poses, point layers, level points, voxels and
// neighbourhoods.
#include "render/scene_adapter.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <tuple>

#include "engine/core/error.h"
#include "engine/model/hierarchy.h"
#include "engine/rollout/level_view.h"
#include "engine/rollout/model_points.h"

namespace dynscope::render {
namespace {

const Color kPickedColor(0.95f, 0.10f, 0.55f);
const Color kObjectEdgeColor(0.10f, 0.35f, 0.85f);
const Color kRelationEdgeColor(1.00f, 0.50f, 0.00f);
const Color kInteractionColor(0.10f, 0.70f, 0.30f);
const Color kDimmedColor(0.78f, 0.78f, 0.78f);
const Color kSourceColor(0.55f, 0.20f, 0.75f);
const Color kFeedColor(0.20f, 0.70f, 0.70f);

// Largest of 1, 2, 5 x 10^k not above `value`.
double round_spacing(double value) {
  const double decade = std::pow(10.0, std::floor(std::log10(value)));
  for (double m : {5.0, 2.0, 1.0}) {
    if (m * decade <= value) return m * decade;
  }
  return decade;
}

std::shared_ptr<PointSeries> single_point(const Vec3& p) {
  Points one(1, 3);
  one.row(0) = p.transpose();
  return make_point_series({one});
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

namespace {

// The list `which` of a trace level, or null.
const TraceList* find_list(const ModelTrace& trace, int level, LevelList which) {
  for (const TraceList& list : trace.levels[static_cast<size_t>(level)].lists) {
    if (list.name == level_list_name(which)) return &list;
  }
  return nullptr;
}

// Row `row` of a trace list as a one-row NeighborList (empty when the list is absent).
NeighborList list_row(const TraceList* list, int row) {
  NeighborList out;
  out.index = IndexMatrix(1, 0);
  out.mask = MaskMatrix(1, 0);
  if (!list || row >= list->index.rows()) return out;
  out.index = list->index.row(row);
  out.mask = list->mask.row(row);
  return out;
}

// ‖h‖ per neighbour of the first traced PointConv at (level, row) over list "level/name".
std::vector<double> filter_weights(const ModelTrace& trace, int level, int row, LevelList which,
                                   std::string* conv) {
  const std::string list = level_list_path(level, which);
  for (const TraceQuery& q : trace.queries) {
    if (q.level != level || q.query_index != row || q.list != list) continue;
    std::vector<double> out(static_cast<size_t>(q.weights.rows()), 0.0);
    for (Eigen::Index k = 0; k < q.weights.rows(); ++k) {
      if (q.mask[static_cast<size_t>(k)]) out[static_cast<size_t>(k)] = q.weights.row(k).norm();
    }
    *conv = q.conv;
    return out;
  }
  return {};
}

// Voxel grids of the model are anchored at (min x, min y, 0) of the level-0 points.
Vec3 trace_grid_anchor(const ModelTrace& trace) {
  const Points& p = trace.levels.front().points;
  if (p.rows() == 0) return Vec3::Zero();
  return Vec3(p.col(0).minCoeff(), p.col(1).minCoeff(), 0.0);
}

}  // namespace

SceneRenderData::SceneRenderData(const Scene& scene, const ViewSpec& view,
                                 std::shared_ptr<const ModelTrace> trace)
    : scene_(scene) {
  scene_.validate();
  view.validate();
  level_ = view.level;
  if (!trace && level_ > 0) {
    throw ValueError("level", "level " + std::to_string(level_) +
                                  " needs the model's hierarchy: pass a trace or a level view");
  }
  voxel_ = view.voxel > 0 ? view.voxel : default_sampling_voxel(scene_.scenario);
  point_radius_ = view.point_radius > 0 ? view.point_radius : static_cast<float>(0.3 * voxel_);
  for (const Object& o : scene_.objects) {
    geometry_.push_back(o.rigid && !o.mesh.empty() ? make_mesh_geometry(o.mesh) : nullptr);
  }
  const ViewLayers& l = view.layers;
  const bool need_points =
      l.ground_truth || l.level_points || l.voxels || (l.neighborhoods && view.picked_point >= 0);
  if (need_points && scene_.num_frames() > 0) {
    PointCloudOptions options;
    options.voxel = voxel_;
    cloud_ = build_point_cloud(scene_, options);
    std::vector<Points> frames;
    frames.reserve(scene_.num_frames());
    for (int f = 0; f < scene_.num_frames(); ++f) frames.push_back(cloud_.positions(scene_, f));
    cloud_series_ = make_point_series(frames);
    cloud_series_->colors = categorical_colors(cloud_.object_id);
  }
  if (trace) {
    set_levels(std::move(trace));
  } else if (cloud_series_) {
    // Level 0 without the model's hierarchy: the sampled points themselves, at every frame.
    level_series_ = cloud_series_;
    level_object_ = cloud_.object_id;
  }
}

void SceneRenderData::set_levels(std::shared_ptr<const ModelTrace> trace) {
  if (!trace) throw ValueError("trace", "no trace or level view given");
  if (level_ >= static_cast<int>(trace->levels.size())) {
    throw ValueError("level", std::to_string(level_) + " is not a level of the model's " +
                                  "hierarchy (it has " + std::to_string(trace->levels.size()) +
                                  ": 0.." + std::to_string(trace->levels.size() - 1) + ")");
  }
  if (trace->frame < 0 || trace->frame >= scene_.num_frames()) {
    throw ValueError("trace", "frame " + std::to_string(trace->frame) +
                                  " is not a frame of the scene (" +
                                  std::to_string(scene_.num_frames()) + " frames)");
  }
  const TraceLevel& level = trace->levels[static_cast<size_t>(level_)];
  level_series_ = make_point_series({level.points});
  level_series_->colors = categorical_colors(level.object_ids);
  level_object_ = level.object_ids;
  trace_ = std::move(trace);
}

int SceneRenderData::level_size() const { return static_cast<int>(level_object_.size()); }

double SceneRenderData::level_voxel() const {
  if (trace_ && level_ > 0) return trace_->levels[static_cast<size_t>(level_)].voxel;
  return voxel_;
}
double SceneRenderData::level_radius() const {
  return trace_ ? trace_->levels[static_cast<size_t>(level_)].radius : 0.0;
}

void SceneRenderData::require_levels(const char* what) const {
  if (!trace_) {
    throw ValueError(what, "needs the model's hierarchy: pass a trace or a level view");
  }
}

void SceneRenderData::check_trace_frame(int frame) const {
  if (trace_ && frame != trace_->frame) {
    throw ValueError("frame", "the model trace holds frame " + std::to_string(trace_->frame) +
                                  " only; level points and neighbourhoods cannot be drawn at "
                                  "frame " +
                                  std::to_string(frame));
  }
}
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
  out.point_style = parse_point_style(view.point_style);
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
  const bool trace_layers =
      l.level_points || l.voxels || (l.neighborhoods && view.picked_point >= 0);
  if (trace_ && trace_layers) check_trace_frame(frame);
  const int level_frame = trace_ ? 0 : frame;  // a trace's level series holds its one frame
  if (l.level_points && level_series_ && (trace_ || !l.ground_truth)) {
    PointLayer layer;
    layer.name = "level " + std::to_string(level_);
    layer.series = level_series_;
    layer.frame = level_frame;
    layer.coloring = dim ? PointColoring::kUniform : PointColoring::kPerPoint;
    layer.color = kDimmedColor;
    layer.radius = dim ? 0.7f * level_radius : level_radius;
    out.points.push_back(layer);
  }
  if (l.voxels && level_series_) {
    const double v = level_voxel();
    const Vec3 anchor = trace_ ? trace_grid_anchor(*trace_) : Vec3::Zero();
    std::set<std::tuple<int64_t, int64_t, int64_t, int32_t>> cells;
    for (int i = 0; i < level_series_->num_points; ++i) {
      const Vec3 p = level_series_->position(level_frame, i) - anchor;
      cells.emplace(static_cast<int64_t>(std::floor(p.x() / v)),
                    static_cast<int64_t>(std::floor(p.y() / v)),
                    static_cast<int64_t>(std::floor(p.z() / v)), level_object_[i]);
    }
    for (const auto& [x, y, z, id] : cells) {
      WireBox box;
      box.min = Eigen::Vector3f(static_cast<float>(x * v + anchor.x()),
                                static_cast<float>(y * v + anchor.y()),
                                static_cast<float>(z * v + anchor.z()));
      box.max = box.min + Eigen::Vector3f::Constant(static_cast<float>(v));
      box.color = categorical_color(id) * 0.7f;
      out.boxes.push_back(box);
    }
  }
  if (l.neighborhoods && view.picked_point >= 0) add_neighborhoods(out, frame, view);
  if (l.interaction_points) add_interaction_points(out, frame);
  return out;
}

SceneRenderData::LevelNeighbors SceneRenderData::level_neighbors(int frame, int picked) const {
  const int n = level_size();
  if (picked < 0 || picked >= n) {
    throw ValueError("picked_point", std::to_string(picked) + " is outside the " +
                                         std::to_string(n) + " points of level " +
                                         std::to_string(level_));
  }
  if (frame < 0 || frame >= num_frames()) {
    throw ValueError(
        "frame", std::to_string(frame) + " is outside [0, " + std::to_string(num_frames()) + ")");
  }
  require_levels("neighborhoods");
  check_trace_frame(frame);
  LevelNeighbors out;
  const ModelTrace& t = *trace_;
  out.positions = t.levels[static_cast<size_t>(level_)].points;
  out.object = level_object_;
  out.same = list_row(find_list(t, level_, LevelList::kSame), picked);
  out.relational = list_row(find_list(t, level_, LevelList::kRelational), picked);
  out.same_weight = filter_weights(t, level_, picked, LevelList::kSame, &out.same_conv);
  out.relational_weight =
      filter_weights(t, level_, picked, LevelList::kRelational, &out.relational_conv);
  if (level_ > 0) {
    const Points& below = t.levels[static_cast<size_t>(level_ - 1)].points;
    const NeighborList down = list_row(find_list(t, level_, LevelList::kDown), picked);
    for (Eigen::Index j = 0; j < down.k(); ++j) {
      if (down.mask(0, j)) out.sources.push_back(down.index(0, j));
    }
    if (const TraceList* up = find_list(t, level_, LevelList::kUp)) {
      for (Eigen::Index row = 0; row < up->index.rows(); ++row) {
        for (Eigen::Index j = 0; j < up->index.cols(); ++j) {
          if (up->mask(row, j) && up->index(row, j) == picked) {
            out.feeds.push_back(static_cast<int32_t>(row));
            break;
          }
        }
      }
    }
    auto rows = [&](const std::vector<int32_t>& idx) {
      Points p(static_cast<Eigen::Index>(idx.size()), 3);
      for (size_t i = 0; i < idx.size(); ++i)
        p.row(static_cast<Eigen::Index>(i)) = below.row(idx[i]);
      return p;
    };
    out.source_positions = rows(out.sources);
    out.feed_positions = rows(out.feeds);
  }
  return out;
}

void SceneRenderData::add_neighborhoods(RenderScene& out, int frame, const ViewSpec& view) const {
  const int picked = view.picked_point;
  const LevelNeighbors nb = level_neighbors(frame, picked);
  const Points& positions = nb.positions;
  LineSet edges;
  edges.name = "neighbourhood";
  edges.width = 2.0f;
  const Vec3 center = positions.row(picked).transpose();
  const float r = point_radius_ * static_cast<float>(std::pow(1.5, level_));
  // One list's neighbours: edges and points in the list's colour, or (when the trace holds the
  // learned filter) points coloured by ‖h(p_k − p_0)‖ through viridis over the list's range.
  auto add_list = [&](const NeighborList& list, const std::vector<double>& weight,
                      const Color& color, bool skip_self, const std::string& name) {
    std::vector<Vec3> ends;
    std::vector<float> scalars;
    for (Eigen::Index k = 0; k < list.k(); ++k) {
      const int32_t j = list.index(0, k);
      if (!list.mask(0, k) || (skip_self && j == picked)) continue;
      edges.add(center, positions.row(j).transpose(), color);
      ends.push_back(positions.row(j).transpose());
      if (!weight.empty()) scalars.push_back(static_cast<float>(weight[static_cast<size_t>(k)]));
    }
    if (ends.empty()) return;
    Points p(static_cast<Eigen::Index>(ends.size()), 3);
    for (size_t i = 0; i < ends.size(); ++i) p.row(static_cast<Eigen::Index>(i)) = ends[i];
    PointLayer layer;
    layer.name = name;
    const std::shared_ptr<PointSeries> series = make_point_series({p});
    series->scalars = scalars;
    layer.series = series;
    layer.coloring = PointColoring::kUniform;
    layer.color = color;
    layer.radius = 1.25f * r;
    layer.pickable = false;
    if (!scalars.empty()) {
      layer.coloring = PointColoring::kScalar;
      layer.colormap = "viridis";
      layer.range_min = 0.0f;
      layer.range_max = std::max(*std::max_element(scalars.begin(), scalars.end()), 1e-6f);
    }
    out.points.push_back(layer);
  };
  add_list(nb.same, nb.same_weight, kObjectEdgeColor, true, "object neighbours");
  add_list(nb.relational, nb.relational_weight, kRelationEdgeColor, false, "relational neighbours");
  // Level k−1 points pooled into the picked point (purple) and those it feeds when upsampling.
  auto add_level_below = [&](const Points& p, const Color& color, const std::string& name) {
    if (p.rows() == 0) return;
    for (Eigen::Index i = 0; i < p.rows(); ++i) edges.add(center, p.row(i).transpose(), color);
    PointLayer layer;
    layer.name = name;
    layer.series = make_point_series({p});
    layer.color = color;
    layer.radius = 0.8f * r / 1.5f;
    layer.pickable = false;
    out.points.push_back(layer);
  };
  add_level_below(nb.source_positions, kSourceColor, "pooled from level below");
  add_level_below(nb.feed_positions, kFeedColor, "fed when upsampling");
  out.lines.push_back(std::move(edges));
  PointLayer highlight;
  highlight.name = "picked point";
  highlight.series = single_point(center);
  highlight.color = kPickedColor;
  highlight.radius = 1.8f * r;
  highlight.pickable = false;
  out.points.push_back(highlight);
}

void SceneRenderData::add_trace_interaction_points(RenderScene& out, int frame) const {
  check_trace_frame(frame);
  const TraceMesh& mesh = trace_->mesh;
  const Points& vertices = trace_->levels.front().points;
  const TraceList* senders = nullptr;
  for (const TraceList& l : mesh.lists) {
    if (l.name == mesh_list_name(MeshList::kSenders)) senders = &l;
  }
  if (mesh.points.rows() == 0) return;
  LineSet pairs, faces;
  pairs.name = "interaction pairs";
  pairs.width = 2.0f;
  faces.name = "interaction faces";
  faces.width = 1.5f;
  std::vector<uint8_t> role(static_cast<size_t>(mesh.points.rows()), 0);  // 1 sender, 2 receiver
  const auto point = [&](int32_t i) -> Vec3 { return mesh.points.row(i).transpose(); };
  for (Eigen::Index r = 0; senders && r < senders->index.rows(); ++r) {
    for (Eigen::Index k = 0; k < senders->index.cols(); ++k) {
      if (!senders->mask(r, k)) continue;
      const int32_t from = senders->index(r, k);
      pairs.add(point(from), point(static_cast<int32_t>(r)), kInteractionColor);
      role[static_cast<size_t>(from)] |= 1;
      role[static_cast<size_t>(r)] |= 2;
    }
  }
  // Outline the face under each paired point: senders orange, receivers green.
  std::set<std::pair<int32_t, uint8_t>> drawn;
  for (Eigen::Index i = 0; i < mesh.points.rows(); ++i) {
    const int32_t f = mesh.face[static_cast<size_t>(i)];
    const uint8_t r = role[static_cast<size_t>(i)];
    if (r == 0 || f < 0 || f >= mesh.faces.rows() || !drawn.emplace(f, r).second) continue;
    const Color c = (r & 2) ? kInteractionColor : kRelationEdgeColor;
    for (int e = 0; e < 3; ++e) {
      faces.add(vertices.row(mesh.faces(f, e)).transpose(),
                vertices.row(mesh.faces(f, (e + 1) % 3)).transpose(), c);
    }
  }
  out.lines.push_back(std::move(pairs));
  out.lines.push_back(std::move(faces));
  PointLayer layer;
  layer.name = "interaction points";
  layer.series = make_point_series({mesh.points});
  layer.color = kInteractionColor;
  layer.radius = 0.6f * point_radius_;
  layer.pickable = false;
  out.points.push_back(layer);
}

void SceneRenderData::add_interaction_points(RenderScene& out, int frame) const {
  require_levels("interaction_points");
  // A model that reads points has no interaction points: nothing to draw (the legend says so).
  if (trace_->has_mesh) add_trace_interaction_points(out, frame);
}

std::vector<std::string> SceneRenderData::legend(const ViewSpec& view) const {
  const ViewLayers& l = view.layers;
  std::vector<std::string> lines;
  if (l.ground_truth) lines.push_back("points: " + std::to_string(cloud_.size()));
  if (l.level_points || l.voxels) {
    char text[96];
    const char* source =
        !trace_ ? "" : (is_level_view(*trace_) ? " (model hierarchy)" : " (model trace)");
    std::snprintf(text, sizeof(text), "level %d: %d points, voxel %.3g%s", level_, level_size(),
                  level_voxel(), source);
    lines.push_back(text);
  }
  if (l.neighborhoods && view.picked_point >= 0) {
    char text[128];
    const TraceList* same = trace_ ? find_list(*trace_, level_, LevelList::kSame) : nullptr;
    const int k = same ? static_cast<int>(same->index.cols()) : 0;
    std::snprintf(text, sizeof(text), "point %d: knn %d (blue), r %.3g (orange)", view.picked_point,
                  k, level_radius());
    lines.push_back(text);
    if (trace_ && !is_level_view(*trace_)) {
      lines.push_back("neighbour colour: norm of h(p_k - p_0) (viridis) where traced");
      if (level_ > 0) lines.push_back("purple: pooled from level below; teal: fed when upsampling");
    }
  }
  if (l.interaction_points) {
    lines.push_back(trace_ && trace_->has_mesh
                        ? "model interaction points: pairs and receiver faces green, senders orange"
                        : "no interaction points: the model reads points, not meshes");
  }
  return lines;
}

bool view_needs_levels(const ViewSpec& view) {
  const ViewLayers& l = view.layers;
  return (view.level > 0 && (l.level_points || l.voxels || l.neighborhoods)) ||
         (l.neighborhoods && view.picked_point >= 0) || l.interaction_points;
}

ModelConfig level_view_config(const Scene& scene, const ViewSpec& view) {
  return dynscope::level_view_config(
      scene, view.layers.interaction_points ? InputMode::kMesh : InputMode::kPoints);
}

std::shared_ptr<LevelViews> make_level_views(const Scene& scene, const ViewSpec& view) {
  SamplingOptions sampling;
  sampling.voxel = view.voxel;
  return std::make_shared<LevelViews>(scene, level_view_config(scene, view), sampling);
}

}  // namespace dynscope::render
