// Helpers shared by the subcommands.
#include "app/cli_util.h"

#include "engine/model/checkpoint_info.h"
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
