// Panel computations of the viewer (no GL): picked point, neighbourhood, contacts, level counts.
#include "app/viewer/scene_inspection.h"

#include <algorithm>

#include "engine/core/error.h"
#include "engine/geometry/neighbors.h"
#include "engine/model/hierarchy.h"
#include "engine/model/model_config.h"
#include "engine/rollout/metrics.h"
#include "engine/rollout/model_points.h"

namespace dynscope::app::viewer {
namespace {

void check_point(const render::SceneRenderData& data, int level_point) {
  const int n = data.level_size();
  if (level_point < 0 || level_point >= n) {
    throw ValueError("picked_point", std::to_string(level_point) + " is outside the " +
                                         std::to_string(n) + " points of the level");
  }
}

void check_frame(const Scene& scene, int frame) {
  if (frame < 0 || frame >= scene.num_frames()) {
    throw ValueError("frame", std::to_string(frame) + " is outside [0, " +
                                  std::to_string(scene.num_frames()) + ")");
  }
}

}  // namespace

Points level_positions(const render::SceneRenderData& data, int frame) {
  check_frame(data.scene(), frame);
  const Points all = data.cloud().positions(data.scene(), frame);
  const std::vector<int32_t>& idx = data.level_indices();
  Points out(static_cast<Eigen::Index>(idx.size()), 3);
  for (size_t i = 0; i < idx.size(); ++i) out.row(static_cast<Eigen::Index>(i)) = all.row(idx[i]);
  return out;
}

PointInfo inspect_point(const render::SceneRenderData& data, int level_point, int frame) {
  check_point(data, level_point);
  check_frame(data.scene(), frame);
  const Scene& scene = data.scene();
  PointInfo info;
  info.level_point = level_point;
  info.cloud_point = data.level_indices()[level_point];
  info.object_id = data.cloud().object_id[info.cloud_point];
  info.object_name = scene.objects[data.cloud().object[info.cloud_point]].name;
  auto at = [&](int f) -> Vec3 {
    return data.cloud().positions(scene, f).row(info.cloud_point).transpose();
  };
  info.position = at(frame);
  const int prev = std::max(0, frame - 1), next = std::min(scene.num_frames() - 1, frame + 1);
  if (next > prev) info.velocity = (at(next) - at(prev)) / ((next - prev) * scene.dt_s);
  return info;
}

Neighborhood point_neighborhood(const render::SceneRenderData& data, int level_point, int frame,
                                int k) {
  check_point(data, level_point);
  check_frame(data.scene(), frame);
  const render::SceneRenderData::LevelNeighbors nb = data.level_neighbors(frame, level_point, k);
  Neighborhood out;
  out.k = k;
  out.radius = data.level_radius();
  auto collect = [&](const NeighborList& list, const std::vector<double>& weights,
                     std::vector<NeighborEntry>& into) {
    for (Eigen::Index j = 0; j < list.index.cols(); ++j) {
      const int32_t p = list.index(0, j);
      if (!list.mask(0, j) || p == level_point) continue;
      const double w = static_cast<size_t>(j) < weights.size() ? weights[j] : -1.0;
      into.push_back(
          {p, nb.object[p], (nb.positions.row(p) - nb.positions.row(level_point)).norm(), w});
    }
  };
  // Valid entries come sorted by distance already (NeighborList's contract).
  collect(nb.same, nb.same_weight, out.object);
  collect(nb.relational, nb.relational_weight, out.relational);
  out.object_conv = nb.same_conv;
  out.relational_conv = nb.relational_conv;
  if (data.trace() != nullptr) out.k = static_cast<int>(nb.same.index.cols());
  return out;
}

std::vector<double> contact_distances(const Scene& scene, const ScenePointCloud& cloud) {
  const int target = scene.find_role(Role::kTarget), zone = scene.find_role(Role::kZone);
  if (target < 0 || zone < 0 || cloud.count_of(target) == 0 || cloud.count_of(zone) == 0) return {};
  std::vector<double> out;
  out.reserve(static_cast<size_t>(scene.num_frames()));
  for (int f = 0; f < scene.num_frames(); ++f) {
    const Points p = cloud.positions(scene, f);
    out.push_back(
        min_distance(select_rows(p, cloud.object, target), select_rows(p, cloud.object, zone)));
  }
  return out;
}

std::string hierarchy_preset(const Scene& scene) { return default_scale_preset(scene.scenario); }

std::vector<LevelCount> level_counts(const Scene& scene, const ScenePointCloud& cloud, int frame) {
  check_frame(scene, frame);
  const HierarchyOptions options =
      HierarchyOptions::from_config(ModelConfig::preset(hierarchy_preset(scene)));
  const Hierarchy h = build_hierarchy(cloud.positions(scene, frame), cloud.object_id, options);
  std::vector<LevelCount> out;
  for (int l = 0; l < h.num_levels(); ++l) {
    const HierarchyLevel& level = h.levels[l];
    LevelCount c;
    c.level = l;
    c.voxel = level.voxel;
    c.radius = level.radius;
    c.points = static_cast<int>(level.points.rows());
    for (int32_t id : level.object_ids) ++c.per_object[id];
    out.push_back(std::move(c));
  }
  return out;
}

PointInfo inspect_trace_point(const ModelTrace& trace, const Scene& scene, int level,
                              int level_point) {
  PointInfo info;
  info.cloud_point = trace_level0_point(trace, level, level_point);  // checks level and point
  const TraceLevel& l = trace.levels[static_cast<size_t>(level)];
  info.level_point = level_point;
  info.object_id = l.object_ids[static_cast<size_t>(level_point)];
  const int object = scene.object_index(info.object_id);
  if (object >= 0) info.object_name = scene.objects[static_cast<size_t>(object)].name;
  info.position = l.points.row(level_point).transpose();
  return info;
}

std::vector<LevelCount> trace_level_counts(const ModelTrace& trace) {
  std::vector<LevelCount> out;
  for (size_t i = 0; i < trace.levels.size(); ++i) {
    const TraceLevel& l = trace.levels[i];
    LevelCount c;
    c.level = static_cast<int>(i);
    c.voxel = l.voxel;
    c.radius = l.radius;
    c.points = static_cast<int>(l.points.rows());
    for (int32_t id : l.object_ids) ++c.per_object[id];
    out.push_back(std::move(c));
  }
  return out;
}

}  // namespace dynscope::app::viewer
