// What a training run has done, kept across sittings: the state archive beside a checkpoint
// (optimiser moments, step, wall time, sittings, best epoch) and the progress record of its recipe.
#pragma once

#include <torch/optim/adam.h>

#include <cstdint>
#include <limits>
#include <string>

namespace dynscope {

/// What a run has done before a resume, kept in the training state beside the optimiser.
struct RunProgress {
  int64_t step = 0;
  double wall_seconds = 0.0;  ///< Summed over every sitting so far.
  int64_t chunks = 0;         ///< Sittings that trained (a started run counts its first).
  int64_t best_step = -1;     ///< Step of the best validation rollout error (-1: none yet).
  double best_val_error = std::numeric_limits<double>::infinity();
};

/// Writes the state for `--resume` atomically to `path`: the optimiser, `p`, the architecture
/// (`config_json`, checked on resume) and the world size. Throws IoError if it cannot be written.
void save_train_state(const std::string& path, torch::optim::Adam& optimizer, const RunProgress& p,
                      const std::string& config_json, int world_size);

/// Reads a state written by save_train_state into `optimizer` and returns its progress. Throws
/// IoError if the file is missing or unreadable, FormatError if it was saved for another
/// architecture or another world size. States written before the wall time, sittings and best
/// epoch were recorded resume with none recorded.
RunProgress load_train_state(const std::string& path, torch::optim::Adam& optimizer,
                             const std::string& config_json, int world_size);

/// The recipe's "progress" record (JSON text): steps done and planned (`total_steps`, the whole
/// schedule), steps per epoch, wall time, sittings and the best epoch if one was validated.
std::string progress_record(const RunProgress& p, int64_t steps, int64_t total_steps,
                            int64_t steps_per_epoch);

}  // namespace dynscope
