// Small helpers shared by the subcommands (formatting, file checks).
#pragma once

#include <string>

#include "engine/core/types.h"
#include "engine/core/progress.h"
#include "engine/io/trace_file.h"
#include "engine/rollout/rollout_runner.h"
#include "engine/scene/rollout.h"
#include "engine/scene/scene.h"
#include "engine/sim/dataset.h"

namespace dynscope::app {

/// "[x0, y0, z0] .. [x1, y1, z1]" with 3 decimals, or "empty".
std::string format_aabb(const Aabb& box);
/// Throws IoError if `path` does not exist or is not a regular readable file.
void require_readable_file(const std::string& path);

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

/// One forward pass of `checkpoint` on `scene` at `frame`, sampled as the checkpoint was trained
/// (its recipe), with the learned filter weights of level `level`'s point `picked` when
/// picked >= 0 (a first pass finds which level-0 point that is). Throws like capture_trace, and
/// ValueError for a level or point the model's hierarchy does not have.
ModelTrace capture_checkpoint_trace(const std::string& checkpoint, const Scene& scene,
                                    const std::string& scene_path, int frame, int level,
                                    int picked);

}  // namespace dynscope::app
