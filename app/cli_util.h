// Small helpers shared by the subcommands (formatting, file checks).
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <utility>
#include <vector>

#include "engine/core/progress.h"
#include "engine/core/types.h"
#include "engine/io/trace_file.h"
#include "engine/rollout/rollout_runner.h"
#include "engine/scene/rollout.h"
#include "engine/scene/scene.h"
#include "engine/sim/dataset.h"

namespace dynscope::app {

/// "[x0, y0, z0] .. [x1, y1, z1]" with 3 decimals, or "empty".
std::string format_aabb(const Aabb& box);

/// The process's command line as main() received it (for launchers that restart the program).
void set_command_line(int argc, char** argv);
const std::vector<std::string>& command_line();
/// Throws IoError if `path` does not exist or is not a regular readable file.
void require_readable_file(const std::string& path);

/// Throws ValueError(`name`, "must be in [lo, hi] ..., got v") unless `v` is a finite number in
/// [lo, hi]; with `lo_open` the lower end is excluded ("(lo, hi]"). `note` is appended to the
/// range, e.g. "(0: all frames)".
void require_in_range(const std::string& name, double v, double lo, double hi, bool lo_open = false,
                      const std::string& note = "");
/// Throws ValueError(`name`, "must be an integer in [lo, hi] ..., got v") unless lo <= v <= hi.
void require_int_in_range(const std::string& name, int64_t v, int64_t lo, int64_t hi,
                          const std::string& note = "");

/// Largest frame count or frame index an option accepts (a larger one is a typing error).
constexpr int64_t kMaxFrameOption = 1000000;
/// Largest voxel edge an option accepts, in scene units.
constexpr double kMaxVoxelOption = 1e6;

/// CLI11 check for an unsigned option (seeds): CLI11 turns "-1" into 2^64 - 1, so a sign or
/// anything but decimal digits is refused with the accepted range.
CLI::Validator unsigned_integer();

/// CLI11 check: a finite number in (lo, hi] (`lo_open`) or [lo, hi]; NaN and inf are refused
/// (CLI11's own PositiveNumber lets NaN through). The message states the range.
CLI::Validator finite_number(double lo, double hi, bool lo_open);

/// Largest --threads a command accepts (the compute-thread budget's bound).
int64_t max_threads_option();

/// An input of a command: the option that named it ("--scene", "input") and its path.
using NamedPath = std::pair<std::string, std::string>;

/// True if `a` and `b` name the same file: the same inode when both exist (hard links and
/// symbolic links included), else the same normalised absolute path.
bool same_file(const std::string& a, const std::string& b);

/// Throws IoError naming `path` unless the directory a file output goes into exists and is
/// writable: checked before any work, so a long run never fails at its very end for a typo.
/// Empty paths are ignored.
void require_output_directory(const std::string& option, const std::string& path);

/// Throws ValueError(`option`, ...) naming the input if writing `output` would replace one of
/// `inputs` (same_file); empty paths are ignored. Called before any work, so a command never
/// destroys what it reads.
void require_distinct_output(const std::string& option, const std::string& output,
                             const std::vector<NamedPath>& inputs);

/// Checks `options` (before the first scene; the output directory is created), then generates
/// the dataset with a progress bar. Throws what check_dataset_options / generate_dataset throw.
DatasetSummary generate_with_progress(const DatasetOptions& options);

/// Rolls `checkpoint` out on `scene` (read from `scene_path`), sampled as the checkpoint was
/// trained unless `voxel` > 0, advancing `progress` once per predicted frame; the result names
/// the scene, the checkpoint and the model config. Throws IoError for a missing checkpoint and
/// what load_model / run_rollout throw.
Rollout rollout_checkpoint(const std::string& checkpoint, const Scene& scene,
                           const std::string& scene_path, const RolloutOptions& options,
                           double voxel = 0.0, Progress* progress = nullptr,
                           ModelPoints* points_out = nullptr);

/// The pass of `checkpoint` that produced frame `frame`+1 of `rollout` (capture_rollout_trace),
/// with the filter weights of level `level`'s point `picked` when picked >= 0; rollout_path is
/// recorded. Throws like capture_rollout_trace and capture_checkpoint_trace.
ModelTrace capture_checkpoint_rollout_trace(const std::string& checkpoint, const Rollout& rollout,
                                            const std::string& rollout_path, int frame, int level,
                                            int picked);

/// One forward pass of `checkpoint` on `scene` at `frame`, sampled as the checkpoint was trained
/// (its recipe), with the learned filter weights of level `level`'s point `picked` when
/// picked >= 0 (a first pass finds which level-0 point that is). Throws like capture_trace, and
/// ValueError for a level or point the model's hierarchy does not have.
ModelTrace capture_checkpoint_trace(const std::string& checkpoint, const Scene& scene,
                                    const std::string& scene_path, int frame, int level,
                                    int picked);

}  // namespace dynscope::app
