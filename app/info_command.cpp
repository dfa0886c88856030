// `dynscope info FILE | --system`: describe a scene, mesh, rollout, trace or checkpoint, or the
// machine and process (BLAS, threads, LibTorch, GL).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <utility>
#include <vector>

#include "app/cli_util.h"
#include "app/commands.h"
#include "engine/core/error.h"
#include "engine/geometry/point_cloud.h"
#include "engine/io/mesh_import.h"
#include "engine/io/rollout_file.h"
#include "engine/io/scene_file.h"
#include "engine/io/trace_file.h"
#include "engine/model/checkpoint_info.h"
#include "engine/model/torch_runtime.h"
#include "engine/rollout/level_view.h"
#include "engine/rollout/model_points.h"
#include "render/context_factory.h"

namespace dynscope::app {
namespace {

struct InfoOptions {
  std::string file;
  double voxel = 0.0;  // 0 = the paper's default for the file's scale
  double oversample = 8.0;
  uint64_t seed = 0;
  bool json = false;
  bool system = false;
};

nlohmann::json aabb_json(const Aabb& box) {
  if (box.empty()) return nullptr;
  return {{"min", {box.min.x(), box.min.y(), box.min.z()}},
          {"max", {box.max.x(), box.max.y(), box.max.z()}}};
}

// The fastest motion in a scene: per object, the largest distance any of its sampled points
// moves between two consecutive frames, and where the fastest of all happens.
struct SceneMotion {
  std::vector<double> max_step;  // per object index
  double fastest = 0.0;
  int fastest_object = -1, fastest_frame = -1;  // frame f: the step from f to f + 1
};

SceneMotion scene_motion(const Scene& scene, const ScenePointCloud& cloud) {
  SceneMotion m;
  m.max_step.assign(scene.objects.size(), 0.0);
  if (scene.num_frames() < 2 || cloud.size() == 0) return m;
  Points previous = cloud.positions(scene, 0);
  for (int f = 1; f < scene.num_frames(); ++f) {
    Points current = cloud.positions(scene, f);
    const Eigen::VectorXd step = (current - previous).rowwise().norm();
    for (Eigen::Index i = 0; i < step.size(); ++i) {
      const auto o = static_cast<size_t>(cloud.object[static_cast<size_t>(i)]);
      m.max_step[o] = std::max(m.max_step[o], step[i]);
      if (step[i] > m.fastest) {
        m.fastest = step[i];
        m.fastest_object = static_cast<int>(o);
        m.fastest_frame = f - 1;
      }
    }
    previous = std::move(current);
  }
  return m;
}

void print_scene(const std::string& path, const Scene& scene, const InfoOptions& opt) {
  const double voxel = opt.voxel > 0 ? opt.voxel : default_sampling_voxel(scene.scenario);
  PointCloudOptions pc_opt;
  pc_opt.voxel = voxel;
  pc_opt.oversample = opt.oversample;
  pc_opt.seed = opt.seed;
  const ScenePointCloud cloud = build_point_cloud(scene, pc_opt);
  const int frames = scene.num_frames();
  const SceneMotion motion = scene_motion(scene, cloud);
  // The level-0 relational radius of the model preset for this scenario: a point that moves
  // farther than it in one frame can pass another object between two of the model's looks.
  const double radius = level_view_config(scene).radius;

  if (opt.json) {
    nlohmann::json j;
    j["file"] = path;
    j["kind"] = "scene";
    j["scenario"] = scene.scenario;
    j["seed"] = scene.seed;
    j["dt_s"] = scene.dt_s;
    j["num_frames"] = frames;
    j["bounds"] = aabb_json(scene.bounds());
    j["voxel"] = voxel;
    j["num_points"] = cloud.size();
    for (size_t i = 0; i < scene.objects.size(); ++i) {
      const Object& o = scene.objects[i];
      const int idx = static_cast<int>(i);
      j["objects"].push_back(
          {{"id", o.id},
           {"name", o.name},
           {"role", role_name(o.role)},
           {"rigid", o.rigid},
           {"vertices", o.mesh.num_vertices()},
           {"faces", o.mesh.num_faces()},
           {"scale", {o.scale.x(), o.scale.y(), o.scale.z()}},
           {"mass", o.mass},
           {"friction", o.friction},
           {"restitution", o.restitution},
           {"bounds_frame0", frames > 0 ? aabb_json(Aabb::of(scene.world_vertices(idx, 0)))
                                        : nlohmann::json(nullptr)},
           {"points", cloud.count_of(idx)},
           {"max_step", motion.max_step[i]}});
    }
    j["motion"] = {{"fastest_step", motion.fastest},
                   {"fastest_object", motion.fastest_object},
                   {"fastest_frame", motion.fastest_frame},
                   {"model_radius", radius}};
    for (const auto& [name, values] : scene.labels) {
      int positive = 0;
      for (double v : values) positive += v > 0.5 ? 1 : 0;
      j["labels"][name] = {{"positive_frames", positive}, {"any", positive > 0}};
    }
    std::cout << j.dump(2) << "\n";
    return;
  }

  std::printf("%s: scene\n", path.c_str());
  std::printf("  scenario   %s (seed %llu)\n", scene.scenario.c_str(),
              static_cast<unsigned long long>(scene.seed));
  std::printf("  frames     %d, dt %.5f s (%.2f fps), duration %.3f s\n", frames, scene.dt_s,
              1.0 / scene.dt_s, frames > 0 ? (frames - 1) * scene.dt_s : 0.0);
  std::printf("  bounds     %s\n", format_aabb(scene.bounds()).c_str());
  std::printf("  objects    %zu\n", scene.objects.size());
  std::printf("  %4s %-16s %-6s %-5s %7s %7s %7s %7s %7s  %-48s %7s %8s\n", "id", "name", "role",
              "rigid", "verts", "faces", "mass", "fric", "rest", "bounds at frame 0", "points",
              "max step");
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const Object& o = scene.objects[i];
    const int idx = static_cast<int>(i);
    const std::string box = frames > 0 ? format_aabb(Aabb::of(scene.world_vertices(idx, 0))) : "-";
    std::printf("  %4d %-16s %-6s %-5s %7ld %7ld %7.3f %7.3f %7.3f  %-48s %7lld %8.4f\n", o.id,
                o.name.c_str(), role_name(o.role), o.rigid ? "yes" : "no",
                static_cast<long>(o.mesh.num_vertices()), static_cast<long>(o.mesh.num_faces()),
                o.mass, o.friction, o.restitution, box.c_str(),
                static_cast<long long>(cloud.count_of(idx)), motion.max_step[i]);
  }
  std::printf(
      "  points     %lld after surface sampling (%.1f samples per voxel area) and grid "
      "downsampling at voxel %.4g\n",
      static_cast<long long>(cloud.size()), opt.oversample, voxel);
  if (motion.fastest_object >= 0) {
    std::printf(
        "  motion     fastest point moves %.4g per frame (%s, frames %d-%d); the level-0 "
        "relational radius of the scenario's model preset is %.4g (%.2fx that step)\n",
        motion.fastest, scene.objects[static_cast<size_t>(motion.fastest_object)].name.c_str(),
        motion.fastest_frame, motion.fastest_frame + 1, radius,
        motion.fastest > 0 ? radius / motion.fastest : 0.0);
  }
  for (const auto& [name, values] : scene.labels) {
    int positive = 0, first = -1;
    for (size_t f = 0; f < values.size(); ++f) {
      if (values[f] > 0.5) {
        ++positive;
        if (first < 0) first = static_cast<int>(f);
      }
    }
    std::printf("  label      %s: %s (%d of %zu frames", name.c_str(), positive > 0 ? "yes" : "no",
                positive, values.size());
    if (first >= 0) std::printf(", first at frame %d", first);
    std::printf(")\n");
  }
}

void print_mesh(const std::string& path, const Mesh& mesh, const InfoOptions& opt) {
  const Aabb box = Aabb::of(mesh.vertices);
  const double diag = box.empty() ? 1.0 : (box.max - box.min).norm();
  const double voxel = opt.voxel > 0 ? opt.voxel : diag / 50.0;
  Scene scene;
  Object object;
  object.name = path;
  object.mesh = mesh;
  scene.objects.push_back(object);
  scene.trajectories.push_back(Trajectory{{Pose{}}, {}});
  PointCloudOptions pc_opt;
  pc_opt.voxel = voxel;
  pc_opt.oversample = opt.oversample;
  pc_opt.seed = opt.seed;
  const auto points = build_point_cloud(scene, pc_opt).size();
  if (opt.json) {
    nlohmann::json j = {{"file", path},
                        {"kind", "mesh"},
                        {"vertices", mesh.num_vertices()},
                        {"faces", mesh.num_faces()},
                        {"area", mesh.area()},
                        {"bounds", aabb_json(box)},
                        {"voxel", voxel},
                        {"points", points}};
    std::cout << j.dump(2) << "\n";
    return;
  }
  std::printf("%s: mesh\n", path.c_str());
  std::printf("  vertices   %ld\n  faces      %ld\n", static_cast<long>(mesh.num_vertices()),
              static_cast<long>(mesh.num_faces()));
  std::printf("  area       %.6g\n  bounds     %s\n", mesh.area(), format_aabb(box).c_str());
  std::printf(
      "  points     %lld after surface sampling (%.1f samples per voxel area) and grid "
      "downsampling at voxel %.4g\n",
      static_cast<long long>(points), opt.oversample, voxel);
}

void print_rollout(const std::string& path, const Rollout& r, const InfoOptions& opt) {
  const int frames = r.num_frames();
  const double end_error = frames > 0 ? r.point_error.back() : 0.0;
  if (opt.json) {
    nlohmann::json j = {{"file", path},
                        {"kind", "rollout"},
                        {"scene", r.scene_path},
                        {"checkpoint", r.checkpoint_path},
                        {"scenario", r.scenario},
                        {"dt_s", r.dt_s},
                        {"num_frames", frames},
                        {"observed_frames", r.observed_frames},
                        {"num_points", r.num_points()},
                        {"num_objects", r.num_objects()},
                        {"sampling_voxel", r.sampling_voxel},
                        {"point_error", r.point_error},
                        {"end_point_error", end_error}};
    if (r.has_contact()) {
      j["contact_distance_truth"] = r.contact_distance_truth;
      j["contact_distance_predicted"] = r.contact_distance_predicted;
    }
    std::cout << j.dump(2) << "\n";
    return;
  }
  std::printf("%s: rollout\n", path.c_str());
  std::printf("  scene      %s (%s)\n", r.scene_path.c_str(), r.scenario.c_str());
  std::printf("  checkpoint %s\n", r.checkpoint_path.empty() ? "-" : r.checkpoint_path.c_str());
  std::printf("  frames     %d (%d observed), dt %.5f s\n", frames, r.observed_frames, r.dt_s);
  std::printf("  points     %ld on %d objects (sampling voxel %.4g)\n",
              static_cast<long>(r.num_points()), r.num_objects(), r.sampling_voxel);
  std::printf("  error      mean point distance %.4g at the last frame\n", end_error);
  if (r.has_contact()) {
    double truth = r.contact_distance_truth.front(), pred = r.contact_distance_predicted.front();
    for (size_t f = 0; f < r.contact_distance_truth.size(); ++f) {
      truth = std::min(truth, r.contact_distance_truth[f]);
      pred = std::min(pred, r.contact_distance_predicted[f]);
    }
    std::printf("  contact    min target-zone distance: truth %.4g, prediction %.4g\n", truth,
                pred);
  }
}

void print_trace(const std::string& path, const ModelTrace& t, const InfoOptions& opt) {
  if (opt.json) {
    nlohmann::json j = {{"file", path},
                        {"kind", "trace"},
                        {"scene", t.scene_path},
                        {"checkpoint", t.checkpoint_path},
                        {"source", t.source},
                        {"rollout", t.rollout_path},
                        {"frame", t.frame},
                        {"mesh", t.has_mesh},
                        {"feature_records", t.features.size()},
                        {"filter_records", t.queries.size()}};
    for (const TraceLevel& level : t.levels) {
      nlohmann::json lists = nlohmann::json::array();
      for (const TraceList& l : level.lists) lists.push_back(l.name);
      j["levels"].push_back({{"points", level.points.rows()},
                             {"voxel", level.voxel},
                             {"radius", level.radius},
                             {"lists", lists}});
    }
    std::cout << j.dump(2) << "\n";
    return;
  }
  std::printf("%s: trace\n", path.c_str());
  std::printf("  scene      %s, frame %d\n", t.scene_path.c_str(), t.frame);
  if (t.source == kTraceSourceRollout) {
    std::printf(
        "  source     rollout %s: the pass that predicted frame %d from its own "
        "predicted frames %d..%d\n",
        t.rollout_path.c_str(), t.frame + 1, t.frame - 2, t.frame);
  } else {
    std::printf("  source     the scene's ground-truth frames %d..%d\n", t.frame - 2, t.frame);
  }
  std::printf("  checkpoint %s\n", t.checkpoint_path.c_str());
  for (size_t l = 0; l < t.levels.size(); ++l) {
    const TraceLevel& level = t.levels[l];
    std::string lists;
    for (const TraceList& list : level.lists) lists += (lists.empty() ? "" : ", ") + list.name;
    std::printf("  level %zu    %6ld points, voxel %.4g, radius %.4g, lists: %s\n", l,
                static_cast<long>(level.points.rows()), level.voxel, level.radius, lists.c_str());
  }
  std::printf("  records    %zu feature-norm, %zu filter-weight%s\n", t.features.size(),
              t.queries.size(), t.has_mesh ? ", mesh interaction points" : "");
}

void print_checkpoint(const std::string& path, const CheckpointInfo& c, const InfoOptions& opt) {
  if (opt.json) {
    nlohmann::json j = {{"file", path},
                        {"kind", "checkpoint"},
                        {"format_version", c.format_version},
                        {"parameters", c.parameter_count},
                        {"config", nlohmann::json::parse(c.config_json)}};
    const auto vec = [](const Vec3& v) { return nlohmann::json::array({v.x(), v.y(), v.z()}); };
    j["stats"] = {{"velocity_mean", vec(c.stats.velocity_mean)},
                  {"velocity_std", vec(c.stats.velocity_std)},
                  {"target_mean", vec(c.stats.target_mean)},
                  {"target_std", vec(c.stats.target_std)},
                  {"z_mean", c.stats.z_mean},
                  {"z_std", c.stats.z_std}};
    std::cout << j.dump(2) << "\n";
    return;
  }
  std::printf("%s: checkpoint (format %lld)\n", path.c_str(),
              static_cast<long long>(c.format_version));
  std::printf("  model      %s, target %s, input %s\n", to_string(c.config.kind).c_str(),
              to_string(c.config.target).c_str(), to_string(c.config.input).c_str());
  std::printf("  size       width %d, %d levels, %lld parameters\n", c.config.width,
              c.config.levels, static_cast<long long>(c.parameter_count));
  const auto row = [](const char* name, const Vec3& mean, const Vec3& std) {
    std::printf("  %-10s mean (%.4g, %.4g, %.4g), std (%.4g, %.4g, %.4g)\n", name, mean.x(),
                mean.y(), mean.z(), std.x(), std.y(), std.z());
  };
  row("velocity", c.stats.velocity_mean, c.stats.velocity_std);
  row(c.config.target == TargetMode::kAcceleration ? "accel" : "target", c.stats.target_mean,
      c.stats.target_std);
  std::printf(
      "  height     mean %.4g, std %.4g (units per frame above; normalisation of the "
      "inputs and the target)\n",
      c.stats.z_mean, c.stats.z_std);
  std::printf("  config     %s\n", c.config_json.c_str());
}

bool starts_with_zip_signature(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char magic[4] = {};
  in.read(magic, 4);
  return in.gcount() == 4 && magic[0] == 'P' && magic[1] == 'K' && magic[2] == 3 && magic[3] == 4;
}

// `info --system`: what this process computes and draws with, as one key/value table.
void print_system(const InfoOptions& opt) {
  std::vector<std::pair<std::string, std::string>> lines = torch_context();
  try {
    lines.emplace_back("gl_headless", render::describe_backend("osmesa"));
  } catch (const std::exception& e) {
    lines.emplace_back("gl_headless", std::string("unavailable: ") + e.what());
  }
  if (opt.json) {
    nlohmann::json j = nlohmann::json::object();
    for (const auto& [key, value] : lines) j[key] = value;
    std::cout << j.dump(2) << "\n";
    return;
  }
  for (const auto& [key, value] : lines) {
    std::printf("%-22s %s\n", key.c_str(), value.c_str());
  }
}

void run_info(const InfoOptions& opt) {
  if (opt.system) {
    print_system(opt);
    if (opt.file.empty()) return;
  }
  if (opt.file.empty()) throw ValueError("file", "give a FILE to describe, or --system");
  require_readable_file(opt.file);
  if (is_rollout_file(opt.file)) {
    print_rollout(opt.file, read_rollout(opt.file), opt);
  } else if (is_trace_file(opt.file)) {
    print_trace(opt.file, read_trace(opt.file), opt);
  } else if (is_hdf5_file(opt.file)) {
    print_scene(opt.file, read_scene(opt.file), opt);
  } else if (is_mesh_file(opt.file)) {
    print_mesh(opt.file, import_mesh(opt.file), opt);
  } else if (starts_with_zip_signature(opt.file)) {  // checkpoints are torch (zip) archives
    print_checkpoint(opt.file, read_checkpoint_info(opt.file), opt);
  } else {
    throw IoError(opt.file,
                  "not a scene, rollout or trace file (HDF5), a mesh assimp can read, or a "
                  "checkpoint");
  }
}

}  // namespace

void add_info_command(CLI::App& app) {
  auto opt = std::make_shared<InfoOptions>();
  CLI::App* cmd = app.add_subcommand(
      "info",
      "Describe a file: a scene (HDF5, dynscope or Physion layout: objects, roles, frames, dt, "
      "bounding boxes, vertex/face counts, model points after surface sampling and grid "
      "downsampling), a mesh (any format assimp reads), a rollout, a trace or a checkpoint.");
  cmd->add_option(
      "file", opt->file,
      "Scene, rollout or trace (.h5), mesh (.obj, .ply, .stl, .glb, ...) or checkpoint file");
  cmd->add_option("--voxel", opt->voxel,
                  "Grid downsampling voxel edge for the point counts (default: 0.2 for movi-* "
                  "scenes, 0.05 for other scenes, bounding-box diagonal / 50 for meshes)")
      ->check(finite_number(0, kMaxVoxelOption, true));
  cmd->add_option("--oversample", opt->oversample,
                  "Surface samples per voxel-face area before downsampling")
      ->check(finite_number(0, 1e4, true))
      ->capture_default_str();
  cmd->add_option("--seed", opt->seed, "Surface sampling seed")
      ->check(unsigned_integer())
      ->capture_default_str();
  cmd->add_flag("--json", opt->json, "Print machine-readable JSON instead of a table");
  cmd->add_flag("--system", opt->system,
                "Describe this machine and process instead: LibTorch version and CUDA, the BLAS "
                "library actually mapped (warns on the reference BLAS), LibTorch/OpenMP/BLAS "
                "thread counts, and the headless GL renderer");
  cmd->callback([opt] { run_info(*opt); });
}

}  // namespace dynscope::app
