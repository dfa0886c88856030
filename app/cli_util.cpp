// Helpers shared by the subcommands.
#include "app/cli_util.h"

#include "engine/model/checkpoint_info.h"
#include "engine/rollout/model_predictor.h"
#include "engine/rollout/trace_capture.h"
#include "engine/train/train_options.h"

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "engine/core/error.h"

namespace dynscope::app {

std::string format_aabb(const Aabb& box) {
  if (box.empty()) return "empty";
  char buf[160];
  std::snprintf(buf, sizeof buf, "[%.3f, %.3f, %.3f] .. [%.3f, %.3f, %.3f]", box.min.x(),
                box.min.y(), box.min.z(), box.max.x(), box.max.y(), box.max.z());
  return buf;
}

void require_readable_file(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(path, ec)) throw IoError(path, "no such file");
  if (!fs::is_regular_file(path, ec)) throw IoError(path, "not a regular file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path, "cannot be opened for reading");
}

DatasetSummary generate_with_progress(const DatasetOptions& options) {
  check_dataset_options(options);
  Progress progress("generate " + options.scenario, options.count);
  const DatasetSummary summary = generate_dataset(options, &progress);
  progress.finish();
  return summary;
}

Rollout rollout_checkpoint(const std::string& checkpoint, const Scene& scene,
                           const std::string& scene_path, const RolloutOptions& options,
                           double voxel, Progress* progress, ModelPoints* points_out) {
  require_readable_file(checkpoint);
  const LoadedModel model = load_model(checkpoint);
  SamplingOptions sampling = checkpoint_sampling(checkpoint, model.config);
  if (voxel > 0) sampling.voxel = voxel;
  ModelPoints points = build_model_points(scene, sampling);
  Rollout r = run_rollout(scene, points, model.predict, options, progress);
  r.scene_path = scene_path;
  r.checkpoint_path = checkpoint;
  r.model_config = model.config_json;
  if (points_out) *points_out = std::move(points);
  return r;
}

ModelTrace capture_checkpoint_trace(const std::string& checkpoint, const Scene& scene,
                                    const std::string& scene_path, int frame, int level,
                                    int picked) {
  require_readable_file(checkpoint);
  const CheckpointInfo info = read_checkpoint_info(checkpoint);
  const ModelPoints points = build_model_points(scene, checkpoint_sampling(checkpoint, info.config));
  ModelTrace trace = capture_trace(checkpoint, scene, points, frame, {});
  if (picked >= 0) {
    const int query = trace_level0_point(trace, level, picked);
    trace = capture_trace(checkpoint, scene, points, frame, {query});
  }
  trace.scene_path = scene_path;
  return trace;
}

}  // namespace dynscope::app
