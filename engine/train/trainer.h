// The training loop: Adam on a Huber loss of p̂(t+1), noise, validation, checkpoints, resume.
#pragma once

#include <cstdint>
#include <vector>

#include "engine/train/train_options.h"

namespace dynscope {

/// Validation numbers of one epoch.
struct EpochReport {
  int epoch = 0;
  int64_t step = 0;                ///< Steps done when the epoch ended.
  double train_loss = 0.0;         ///< Mean training loss over the epoch's steps.
  double val_loss = 0.0;           ///< Loss on fixed validation frames without noise (NaN: no val).
  double val_rollout_error = 0.0;  ///< Mean last-frame point error of short validation rollouts.
};

/// What a training run did.
struct TrainResult {
  int64_t start_step = 0;  ///< Step the run started from (> 0 when resumed).
  int64_t steps = 0;       ///< Total steps done (including resumed ones).
  int64_t steps_per_epoch = 0;
  double last_loss = 0.0;
  std::vector<EpochReport> epochs;
};

/// Trains a model as `options` says (options.resolve() is applied with the dataset's scenario).
/// Reads DIR/manifest.json train and val splits, computes normalisation statistics from the
/// training scenes, and runs Adam: every step draws `batch` items of a per-epoch shuffled list in
/// which each training scene appears samples_per_scene times, one uniformly random frame t each
/// (t−2 … t+1 must exist), adds random-walk noise to the input velocities and minimises the
/// Huber loss of p̂(t+1) against p(t+1) (per component, in target-std units, averaged over all
/// points of the batch). Every random choice derives from (seed, epoch or step), so a resumed run
/// repeats exactly what an uninterrupted one does. Writes the checkpoint, CKPT.state (optimiser
/// state and step) and CKPT.recipe.json every checkpoint_every steps and at the end, each
/// atomically. Shows a progress bar with loss and ETA on stderr when `show_progress`. Throws
/// ValueError/IoError/FormatError for bad options, data or a resume state that does not match
/// (naming the file); LibTorch errors become dynscope Error.
TrainResult train_model(TrainOptions options, bool show_progress = false);

}  // namespace dynscope
