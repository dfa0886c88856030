// The training loop: Adam on a Huber loss of p̂(t+1), noise, validation, checkpoints, resume.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "engine/train/train_options.h"
#include "engine/train/velocity_noise.h"

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
  std::vector<double> losses;  ///< Loss of every step of this run (over all ranks' examples).
  std::vector<EpochReport> epochs;
  int world_size = 1;
  /// FNV-1a of the parameters' bytes at the end (equal on every rank of a data-parallel run).
  uint64_t parameter_digest = 0;
  double allreduce_seconds = 0.0;  ///< Time inside the gradient all-reduces (data-parallel).
  double train_seconds = 0.0;      ///< Wall time of the steps.
  double wall_seconds = 0.0;       ///< Wall time of the run, summed over every chunk (resumes).
  int64_t chunks = 0;              ///< Sittings of the run: 1, plus one per resume.
  int64_t best_step = -1;          ///< Step of the best validation rollout error (-1: none).
};

class ProcessGroup;
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
///
/// With a `group` of W ranks (data-parallel, every rank calls this with the same options): rank 0
/// computes the normalisation statistics and its parameters are broadcast; each step's
/// batch × W examples come from the one seeded epoch order exactly as one process with batch
/// batch × W would draw them, and rank r trains on the r-th batch of them; the loss is normalised
/// by the points of all W batches and the gradients are summed by bucketed all-reduces, so every
/// rank holds identical parameters and the loss curve is that of the single process. Rank 0 alone
/// writes checkpoint, state, recipe and log and validates. --resume needs the checkpoint and
/// state readable by every rank (a shared directory) and the same world size. At the end the
/// ranks' parameter digests are compared (Error if they differ).
TrainResult train_model(TrainOptions options, bool show_progress = false,
                        ProcessGroup* group = nullptr);

}  // namespace dynscope
