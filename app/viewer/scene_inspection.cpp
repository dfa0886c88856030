// Panel computations of the viewer (no GL): picked point, neighbourhood, contacts, level counts.
#include "app/viewer/scene_inspection.h"

#include <algorithm>

#include "engine/core/error.h"
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
  if (const ModelTrace* trace = data.trace()) {
    if (frame != trace->frame) {
      throw ValueError("frame", "the model's levels are of frame " + std::to_string(trace->frame) +
                                    ", not " + std::to_string(frame));
    }
    return trace->levels[static_cast<size_t>(data.level())].points;
  }
  return data.cloud().positions(data.scene(), frame);
}

PointInfo inspect_point(const render::SceneRenderData& data, int level_point, int frame) {
  check_point(data, level_point);
  check_frame(data.scene(), frame);
  const Scene& scene = data.scene();
  const ScenePointCloud& cloud = data.cloud();
  PointInfo info;
  int cloud_point = level_point;
  if (const ModelTrace* trace = data.trace()) {
    if (frame != trace->frame) {
      throw ValueError("frame", "the model's levels are of frame " + std::to_string(trace->frame) +
                                    ", not " + std::to_string(frame));
    }
    info = inspect_trace_point(*trace, scene, data.level(), level_point);
    // The model's points are the sampled cloud when they coincide with it at the frame; then the
    // point keeps its identity over frames and has a velocity.
    cloud_point = -1;
    const Points& model = trace->levels.front().points;
    if (cloud.size() == model.rows() && info.cloud_point >= 0 &&
        (cloud.positions(scene, frame).row(info.cloud_point) - model.row(info.cloud_point)).norm() <
            1e-9) {
      cloud_point = info.cloud_point;
    }
  } else {
    info.level_point = level_point;
    info.cloud_point = level_point;
    info.object_id = cloud.object_id[static_cast<size_t>(level_point)];
    info.object_name = scene.objects[static_cast<size_t>(cloud.object[level_point])].name;
    info.position = cloud.positions(scene, frame).row(level_point).transpose();
  }
  if (cloud_point < 0) return info;
  auto at = [&](int f) -> Vec3 { return cloud.positions(scene, f).row(cloud_point).transpose(); };
  const int prev = std::max(0, frame - 1), next = std::min(scene.num_frames() - 1, frame + 1);
  if (next > prev) info.velocity = (at(next) - at(prev)) / ((next - prev) * scene.dt_s);
  info.has_velocity = true;
  return info;
}

Neighborhood point_neighborhood(const render::SceneRenderData& data, int level_point, int frame) {
  check_point(data, level_point);
  check_frame(data.scene(), frame);
  const render::SceneRenderData::LevelNeighbors nb = data.level_neighbors(frame, level_point);
  Neighborhood out;
  out.k = static_cast<int>(nb.same.index.cols());
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

ListDifference neighbor_difference(const ModelTrace& a, const ModelTrace& b, LevelList list,
                                   int point) {
  auto row = [&](const ModelTrace& t) {
    std::vector<int> out;
    if (t.levels.empty()) return out;
    for (const TraceList& l : t.levels.front().lists) {
      if (l.name != level_list_name(list) || point < 0 || point >= l.index.rows()) continue;
      for (Eigen::Index k = 0; k < l.index.cols(); ++k) {
        if (l.mask(point, k) && l.index(point, k) != point) out.push_back(l.index(point, k));
      }
    }
    return out;
  };
  const std::vector<int> ra = row(a), rb = row(b);
  ListDifference d;
  for (int i : ra) {
    if (std::find(rb.begin(), rb.end(), i) == rb.end()) d.only_a.push_back(i);
  }
  for (int i : rb) {
    if (std::find(ra.begin(), ra.end(), i) == ra.end()) d.only_b.push_back(i);
  }
  return d;
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
