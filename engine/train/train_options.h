// Training options ("recipe"): plain data with a JSON round trip, resolved against the dataset.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "engine/model/model_config.h"
#include "engine/rollout/model_points.h"

namespace dynscope {

/// Everything `dynscope train` needs. Zero-valued "auto" fields are filled by resolve() from the
/// dataset's scale (paper supplement: Kubric lr 5e-3, 15 epochs, N = 2; Physion lr 1e-3,
/// 30 epochs, N = 8).
/// A dataset a recipe can create itself: `dynscope generate --scenario S --count N --seed SEED
/// --out DIR`, run by `dynscope train` when DIR has no manifest yet.
struct DatasetRecipe {
  std::string out;
  std::string scenario;
  int64_t count = 0;
  uint64_t seed = 0;
  double frame_rate_hz = 0;            ///< 0: the scenario's own (generate --frame-rate).
  int hide_outcome_frames = 0;         ///< generate --hide-outcome (0: none).
  bool balance = false;                ///< generate --balance.
  std::string mesh_density = "dense";  ///< generate --mesh-density ("dense" or "sparse").
};

struct TrainOptions {
  std::vector<std::string> data_dirs;   ///< One or more `dynscope generate` outputs, all of one
                                        ///< scale (e.g. every Physion-like scenario).
  std::vector<DatasetRecipe> datasets;  ///< How to regenerate data_dirs (recipe files).
  std::string description;              ///< What the recipe trains (free text).
  std::string notes_json;               ///< "notes" of a recipe file (any JSON, kept verbatim):
                                        ///< wall time, dataset size, final losses of the run.
  std::string progress_json;            ///< "progress" of a checkpoint's recipe (JSON object,
                                        ///< written by training, kept verbatim): steps done and
                                        ///< planned, wall time and chunks summed over resumes,
                                        ///< the epoch with the best validation rollout error.
  std::string out;            ///< Checkpoint path; CKPT.state and CKPT.recipe.json sit next to it.
  std::string scale;          ///< "kubric" | "physion" | "" (from the scenario: movi-* → kubric).
  ModelConfig model;          ///< Architecture; voxel and radius come from the scale preset unless
                              ///< set_voxel/set_radius.
  bool set_voxel = false;     ///< model.voxel was given explicitly.
  bool set_radius = false;    ///< model.radius (and model.interaction_threshold) was given
                              ///< explicitly; otherwise both come from the scale preset.
  bool faces = true;          ///< Mesh input: interaction-point reasoning; off runs the point
                              ///< model on the simplified mesh vertices.
  SamplingOptions sampling;   ///< Model points (input follows `model.input`).
  int epochs = 0;             ///< 0: 15 (kubric) / 30 (physion).
  int samples_per_scene = 0;  ///< N draws per training scene per epoch; 0: 2 / 8.
  int batch = 1;              ///< Scenes (one random frame each) per optimiser step and rank.
  int world_size = 1;         ///< Data-parallel ranks (`--nproc`); the effective batch is
                              ///< batch × world_size (the same examples, steps and lr as one
                              ///< process with that batch).
  double lr = 0.0;            ///< Adam learning rate; 0: 5e-3 / 1e-3.
  /// "constant", or "cosine": the learning rate of step s of S decays from lr to
  /// kCosineFinalFraction × lr along half a cosine (learning_rate_at).
  std::string lr_schedule = "constant";
  double noise_std = 3e-4;  ///< Std of the random-walk noise on input velocities (units/frame).
  /// "point": every point draws its own noise; "object": one draw per object, shared by its
  /// points, so every object stays rigid as in a rigid-projected rollout; "centred": per point,
  /// less the object's mean, so no object as a whole moves (add_velocity_noise).
  std::string noise_mode = "point";
  double huber_delta = 1.0;  ///< Huber transition point in target-std units.
  /// Most frames an example is pushed forward by the model before its loss is taken: for a drawn
  /// loss frame t and n drawn from 0 to this number, the state at t − n is made (with its noise),
  /// the model predicts n steps from it without gradient as a rollout does (held static points,
  /// rigid projection), and the loss compares its next prediction with the true p(t + 1).
  /// 0: the loss is always taken at the drawn state itself.
  int pushforward_steps = 0;
  int64_t max_steps = 0;       ///< Stop after this many steps in total (0: all epochs).
  int checkpoint_every = 200;  ///< Write checkpoint and training state every N steps.
  int val_scenes = 4;          ///< Validation scenes used for the loss and the short rollout.
  int val_frames = 8;          ///< Frames of the validation rollout (observed ones included).
  int threads = 0;             ///< torch::set_num_threads (0: LibTorch's default).
  uint64_t seed = 0;  ///< Seeds scene order, frames, noise, and initialisation unless init_seed.
  /// Seeds the initial weights alone when set, so two runs can share their data draws (scene
  /// order, frames, noise: `seed`) and differ only in initialisation, or the reverse.
  std::optional<uint64_t> init_seed;
  std::string log_csv;       ///< Per-step CSV log ("" = none).
  bool keep_epochs = false;  ///< Also keep every epoch's checkpoint (epoch_checkpoint_path).
  bool resume = false;       ///< Continue from `out` and its .state file.

  /// JSON object with every field (the recipe file format).
  std::string to_json() const;
  /// Applies the fields present in `text` over `base` (missing fields keep base's values). Throws
  /// FormatError(source, field, ...) on malformed JSON, wrong types or unknown names.
  static TrainOptions from_json(const std::string& text, const std::string& source,
                                const TrainOptions& base);
  /// from_json over default options.
  static TrainOptions from_json(const std::string& text, const std::string& source);
  /// Fills the automatic fields for `scenario` and validates. Throws ValueError naming the field.
  void resolve(const std::string& scenario);
};

/// Final learning rate of the cosine schedule, as a fraction of the initial one.
constexpr double kCosineFinalFraction = 0.01;

/// Learning rate of step `step` (0-based) of a run of `total` steps under `o.lr_schedule`.
double learning_rate_at(const TrainOptions& o, int64_t step, int64_t total);

/// CKPT + ".state": optimiser state and step for --resume.
std::string train_state_path(const std::string& checkpoint);
/// CKPT + ".recipe.json": the resolved options, read back by rollout, eval and trace.
std::string recipe_path(const std::string& checkpoint);
/// The checkpoint with the lowest validation rollout error of a run writing `checkpoint`: X.pt
/// becomes X.best.pt (any other name gets ".best.pt" appended); it has its own recipe file.
std::string best_checkpoint_path(const std::string& checkpoint);
/// The checkpoint at the end of epoch `epoch` (1-based) of a run writing `checkpoint` with
/// keep_epochs: X.pt becomes X.epoch03.pt (any other name gets ".epoch03.pt" appended); it has its
/// own recipe file.
std::string epoch_checkpoint_path(const std::string& checkpoint, int epoch);

/// Sampling a checkpoint was trained with: its recipe file when present, else the defaults for
/// the scenario with `input` from the model config. Throws FormatError for a malformed recipe.
SamplingOptions checkpoint_sampling(const std::string& checkpoint, const ModelConfig& config);

}  // namespace dynscope
