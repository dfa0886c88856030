// Model point sampling from scenes (point clouds or simplified meshes).
#include "engine/rollout/model_points.h"

#include "engine/core/error.h"
#include "engine/geometry/mesh_simplify.h"

namespace dynscope {

namespace {

bool is_kubric(const std::string& scenario) { return scenario.rfind("movi", 0) == 0; }

}  // namespace

double default_sampling_voxel(const std::string& scenario) {
  return is_kubric(scenario) ? 0.2 : 0.05;
}

std::string default_scale_preset(const std::string& scenario) {
  return is_kubric(scenario) ? "kubric" : "physion";
}

double default_gravity(const std::string& scenario) { return is_kubric(scenario) ? 10.0 : 9.81; }

ModelPoints build_model_points(const Scene& scene, const SamplingOptions& options) {
  ModelPoints out;
  out.voxel = options.voxel > 0 ? options.voxel : default_sampling_voxel(scene.scenario);
  if (options.input == InputMode::kPoints) {
    PointCloudOptions pc;
    pc.voxel = out.voxel;
    pc.oversample = options.oversample;
    pc.seed = options.seed;
    out.cloud = build_point_cloud(scene, pc);
    return out;
  }
  scene.validate();
  std::vector<Mesh> meshes;
  Eigen::Index total_v = 0, total_f = 0;
  for (const Object& o : scene.objects) {
    if (!o.rigid) {
      throw ValueError("object " + std::to_string(o.id),
                       "mesh input supports rigid objects only (" + o.name + " is deformable)");
    }
    meshes.push_back(simplify_vertex_clustering(o.scaled_mesh(), out.voxel));
    total_v += meshes.back().vertices.rows();
    total_f += meshes.back().faces.rows();
  }
  out.cloud.rest.resize(total_v, 3);
  out.faces.resize(total_f, 3);
  Eigen::Index v0 = 0, f0 = 0;
  for (size_t i = 0; i < meshes.size(); ++i) {
    const Mesh& m = meshes[i];
    out.cloud.rest.middleRows(v0, m.vertices.rows()) = m.vertices;
    out.faces.middleRows(f0, m.faces.rows()) = m.faces.array() + static_cast<int32_t>(v0);
    for (Eigen::Index v = 0; v < m.vertices.rows(); ++v) {
      out.cloud.object.push_back(static_cast<int32_t>(i));
      out.cloud.object_id.push_back(scene.objects[i].id);
      out.cloud.particle.push_back(-1);
    }
    v0 += m.vertices.rows();
    f0 += m.faces.rows();
  }
  return out;
}

}  // namespace dynscope
