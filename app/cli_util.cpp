// Helpers shared by the subcommands.
#include "app/cli_util.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "engine/core/error.h"
#include "engine/core/threads.h"
#include "engine/model/checkpoint_info.h"
#include "engine/rollout/model_predictor.h"
#include "engine/rollout/trace_capture.h"
#include "engine/train/train_options.h"

namespace dynscope::app {

namespace {
std::vector<std::string>& stored_command_line() {
  static std::vector<std::string> line;
  return line;
}
}  // namespace

void set_command_line(int argc, char** argv) { stored_command_line().assign(argv, argv + argc); }

const std::vector<std::string>& command_line() { return stored_command_line(); }

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

namespace {

std::string number_text(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

}  // namespace

void require_in_range(const std::string& name, double v, double lo, double hi, bool lo_open,
                      const std::string& note) {
  const bool ok = std::isfinite(v) && (lo_open ? v > lo : v >= lo) && v <= hi;
  if (ok) return;
  throw ValueError(name, std::string("must be a finite number in ") + (lo_open ? "(" : "[") +
                             number_text(lo) + ", " + number_text(hi) + "]" +
                             (note.empty() ? "" : " " + note) + ", got " + number_text(v));
}

void require_int_in_range(const std::string& name, int64_t v, int64_t lo, int64_t hi,
                          const std::string& note) {
  if (v >= lo && v <= hi) return;
  throw ValueError(name, "must be an integer in [" + std::to_string(lo) + ", " +
                             std::to_string(hi) + "]" + (note.empty() ? "" : " " + note) +
                             ", got " + std::to_string(v));
}

CLI::Validator unsigned_integer() {
  return CLI::Validator(
      [](std::string& value) -> std::string {
        const bool digits = !value.empty() && value.size() <= 20 &&
                            value.find_first_not_of("0123456789") == std::string::npos;
        if (digits && (value.size() < 20 || value <= "18446744073709551615")) return "";
        return "must be an integer in [0, 18446744073709551615], got " + value;
      },
      "UINT64");
}

CLI::Validator finite_number(double lo, double hi, bool lo_open) {
  return CLI::Validator(
      [lo, hi, lo_open](std::string& value) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(value.c_str(), &end);
        const bool parsed = !value.empty() && end == value.c_str() + value.size();
        if (parsed && std::isfinite(v) && (lo_open ? v > lo : v >= lo) && v <= hi) return "";
        return std::string("must be a finite number in ") + (lo_open ? "(" : "[") +
               number_text(lo) + ", " + number_text(hi) + "], got " + value;
      },
      "NUMBER");
}

int64_t max_threads_option() { return kMaxComputeThreads; }

bool same_file(const std::string& a, const std::string& b) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::exists(a, ec) && fs::exists(b, ec)) {
    const bool same = fs::equivalent(a, b, ec);
    if (!ec) return same;
  }
  auto normal = [](const std::string& p) {
    std::error_code e;
    const fs::path absolute = fs::absolute(p, e).lexically_normal();
    const fs::path canonical = fs::weakly_canonical(absolute, e);
    return e ? absolute : canonical;
  };
  return normal(a) == normal(b);
}

void require_output_directory(const std::string& option, const std::string& path) {
  if (path.empty()) return;
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::path dir = fs::path(path).parent_path();
  if (dir.empty()) dir = ".";
  if (!fs::is_directory(dir, ec)) {
    throw IoError(
        path, option + ": the directory '" + dir.string() + "' does not exist (create it first)");
  }
  if (access(dir.c_str(), W_OK) != 0) {
    throw IoError(path, option + ": the directory '" + dir.string() + "' is not writable");
  }
  if (fs::is_directory(path, ec)) throw IoError(path, option + ": is a directory, not a file");
}

void require_distinct_output(const std::string& option, const std::string& output,
                             const std::vector<NamedPath>& inputs) {
  if (output.empty()) return;
  for (const auto& [input_option, input] : inputs) {
    if (input.empty() || !same_file(output, input)) continue;
    throw ValueError(option,
                     "'" + output + "' is the " + input_option +
                         " file; writing it would destroy that input (choose another path)");
  }
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

ModelTrace capture_checkpoint_rollout_trace(const std::string& checkpoint, const Rollout& rollout,
                                            const std::string& rollout_path, int frame, int level,
                                            int picked) {
  require_readable_file(checkpoint);
  ModelTrace trace = capture_rollout_trace(checkpoint, rollout, frame, {});
  if (picked >= 0) {
    const int query = trace_level0_point(trace, level, picked);
    trace = capture_rollout_trace(checkpoint, rollout, frame, {query});
  }
  trace.rollout_path = rollout_path;
  return trace;
}

ModelTrace capture_checkpoint_trace(const std::string& checkpoint, const Scene& scene,
                                    const std::string& scene_path, int frame, int level,
                                    int picked) {
  require_readable_file(checkpoint);
  const CheckpointInfo info = read_checkpoint_info(checkpoint);
  const ModelPoints points =
      build_model_points(scene, checkpoint_sampling(checkpoint, info.config));
  ModelTrace trace = capture_trace(checkpoint, scene, points, frame, {});
  if (picked >= 0) {
    const int query = trace_level0_point(trace, level, picked);
    trace = capture_trace(checkpoint, scene, points, frame, {query});
  }
  trace.scene_path = scene_path;
  return trace;
}

}  // namespace dynscope::app
