// Level views: the model's own hierarchy as a trace of structure only.
#include "engine/rollout/level_view.h"

#include <string>

#include "engine/core/error.h"

namespace dynscope {

namespace {

void add_list(std::vector<TraceList>& out, const std::string& name, const NeighborList& list,
              int query_level, int source_level) {
  if (list.rows() == 0 || list.k() == 0) return;
  out.push_back({name, query_level, source_level, list.index, list.mask});
}

}  // namespace

ModelTrace hierarchy_trace(const Hierarchy& h, const Faces& faces, int frame,
                           const ModelConfig& config) {
  ModelTrace t;
  t.model_config = config.to_json();
  t.frame = frame;
  for (int l = 0; l < h.num_levels(); ++l) {
    const HierarchyLevel& src = h.levels[static_cast<size_t>(l)];
    TraceLevel lv;
    lv.points = src.points;
    lv.object_ids = src.object_ids;
    lv.kept = src.kept;
    lv.voxel = src.voxel;
    lv.radius = src.radius;
    for (LevelList list : kLevelLists) {
      add_list(lv.lists, level_list_name(list), level_list(src, list), list_query_level(list, l),
               list_source_level(list, l));
    }
    t.levels.push_back(std::move(lv));
  }
  if (h.has_mesh) {
    t.has_mesh = true;
    t.mesh.faces = faces;
    t.mesh.points = h.mesh.points;
    t.mesh.face = h.mesh.face;
    t.mesh.object_ids = h.mesh.object_ids;
    // Levels here: −1 stands for the interaction points, 0 for the vertices.
    for (MeshList list : kMeshLists) {
      add_list(t.mesh.lists, mesh_list_name(list), mesh_list(h.mesh, list),
               mesh_list_query_level(list), mesh_list_source_level(list));
    }
  }
  return t;
}

ModelTrace level_view(const Scene& scene, const ModelPoints& points, int frame,
                      const ModelConfig& config) {
  if (frame < 0 || frame >= scene.num_frames()) {
    throw ValueError("frame", std::to_string(frame) + " is outside the scene's [0, " +
                                  std::to_string(scene.num_frames()) + ")");
  }
  const Hierarchy h = build_model_hierarchy(points.positions(scene, frame), points.cloud.object_id,
                                            points.faces, config);
  return hierarchy_trace(h, points.faces, frame, config);
}

bool is_level_view(const ModelTrace& trace) {
  return trace.features.empty() && trace.queries.empty();
}

ModelConfig level_view_config(const Scene& scene, InputMode input) {
  ModelConfig c = ModelConfig::preset(default_scale_preset(scene.scenario));
  c.input = input;
  return c;
}

LevelViews::LevelViews(const Scene& scene, const ModelConfig& config, SamplingOptions sampling)
    : scene_(scene), config_(config) {
  config_.validate();
  sampling.input = config_.input;
  points_ = build_model_points(scene_, sampling);
}

std::shared_ptr<const ModelTrace> LevelViews::at(int frame) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (last_ && last_->frame == frame) return last_;
  last_ = std::make_shared<const ModelTrace>(level_view(scene_, points_, frame, config_));
  return last_;
}

std::shared_ptr<const ModelTrace> LevelViews::cached(int frame) {
  std::lock_guard<std::mutex> lock(mutex_);
  return last_ && last_->frame == frame ? last_ : nullptr;
}

}  // namespace dynscope
