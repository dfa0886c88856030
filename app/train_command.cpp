// `dynscope train`: train a dynamics model on a generated dataset (options or a recipe file).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "app/cli_util.h"
#include "app/commands.h"
#include "app/distributed_cli.h"
#include "engine/core/error.h"
#include "engine/core/log.h"
#include "engine/core/threads.h"
#include "engine/io/temp_file.h"
#include "engine/sim/shapes.h"
#include "engine/train/process_group.h"
#include "engine/train/trainer.h"

namespace dynscope::app {
namespace {

// Raw option values; only the options given on the command line override the recipe.
struct TrainArgs {
  std::string recipe;
  std::vector<std::string> data;
  std::string out, model, target, input, faces, scale, log, lr_schedule, noise_mode;
  int epochs = 0, samples = 0, batch = 0, threads = 0, checkpoint_every = 0, width = 0, levels = 0,
      bottleneck = 0, stem = 0, k = 0, c_mid = 0, val_scenes = -1, val_frames = 0, pushforward = 0;
  int64_t max_steps = 0;
  double lr = 0, noise_std = -1, huber_delta = 0, voxel = 0, radius = 0, sample_voxel = 0;
  uint64_t seed = 0, init_seed = 0;
  bool resume = false, keep_epochs = false, hold_static = false, relational_top_only = false;
  DistributedArgs dist;
  CLI::App* cmd = nullptr;
};

bool given(const TrainArgs& a, const char* name) { return a.cmd->count(name) > 0; }

TrainOptions build_options(const TrainArgs& a) {
  TrainOptions o;
  if (!a.recipe.empty()) {
    require_readable_file(a.recipe);
    o = TrainOptions::from_json(read_text_file(a.recipe), a.recipe);
  }
  if (given(a, "--data")) o.data_dirs = a.data;
  if (given(a, "--out")) o.out = a.out;
  if (given(a, "--model")) o.model.kind = parse_model_kind(a.model);
  if (given(a, "--target")) o.model.target = parse_target_mode(a.target);
  if (given(a, "--input")) o.model.input = parse_input_mode(a.input);
  if (given(a, "--faces")) {
    if (a.faces != "on" && a.faces != "off") throw ValueError("faces", "must be on or off");
    o.faces = a.faces == "on";
  }
  if (given(a, "--scale")) o.scale = a.scale;
  if (given(a, "--log")) o.log_csv = a.log;
  if (given(a, "--epochs")) o.epochs = a.epochs;
  if (given(a, "--samples-per-scene")) o.samples_per_scene = a.samples;
  if (given(a, "--batch")) o.batch = a.batch;
  if (given(a, "--threads")) o.threads = a.threads;
  if (given(a, "--checkpoint-every")) o.checkpoint_every = a.checkpoint_every;
  if (given(a, "--max-steps")) o.max_steps = a.max_steps;
  if (given(a, "--lr")) o.lr = a.lr;
  if (given(a, "--lr-schedule")) o.lr_schedule = a.lr_schedule;
  if (given(a, "--noise-std")) o.noise_std = a.noise_std;
  if (given(a, "--noise-mode")) o.noise_mode = a.noise_mode;
  if (given(a, "--keep-epochs")) o.keep_epochs = a.keep_epochs;
  if (given(a, "--hold-static")) o.model.hold_static = a.hold_static;
  if (given(a, "--relational-top-only")) o.model.relational_top_only = a.relational_top_only;
  if (given(a, "--huber-delta")) o.huber_delta = a.huber_delta;
  if (given(a, "--pushforward")) o.pushforward_steps = a.pushforward;
  if (given(a, "--seed")) o.seed = a.seed;
  if (given(a, "--init-seed")) o.init_seed = a.init_seed;
  if (given(a, "--width")) o.model.width = a.width;
  if (given(a, "--levels")) o.model.levels = a.levels;
  if (given(a, "--bottleneck-blocks")) o.model.bottleneck_blocks = a.bottleneck;
  if (given(a, "--stem-blocks")) o.model.stem_blocks = a.stem;
  if (given(a, "--k")) {
    o.model.k = a.k;
    o.model.k_relational = a.k;
  }
  if (given(a, "--c-mid")) o.model.c_mid = a.c_mid;
  if (given(a, "--voxel")) {
    o.model.voxel = a.voxel;
    o.set_voxel = true;
  }
  if (given(a, "--radius")) {
    o.model.radius = a.radius;
    o.set_radius = true;
  }
  if (given(a, "--sample-voxel")) o.sampling.voxel = a.sample_voxel;
  if (given(a, "--val-scenes")) o.val_scenes = a.val_scenes;
  if (given(a, "--val-frames")) o.val_frames = a.val_frames;
  o.resume = a.resume;
  if (o.data_dirs.empty()) throw ValueError("data", "no dataset directory (--data or recipe)");
  if (o.out.empty()) throw ValueError("out", "no checkpoint path (--out or recipe)");
  require_output_directory("--out", o.out);
  for (size_t i = 0; i < o.datasets.size(); ++i) {
    parse_mesh_density(o.datasets[i].mesh_density,
                       "recipe datasets[" + std::to_string(i) + "].mesh_density");
  }
  if (!o.log_csv.empty()) {
    // A recipe's log lives under out/, which a fresh clone does not have yet: make its directory
    // (an existing file where a directory should be is reported just below, before any work).
    std::error_code ignored;
    std::filesystem::create_directories(std::filesystem::path(o.log_csv).parent_path(), ignored);
    require_output_directory("--log", o.log_csv);
  }
  return o;
}

// A recipe's "datasets" are generated when their directory has no manifest yet, so that one
// `dynscope train --recipe FILE` reproduces a checkpoint from nothing.
void generate_missing_datasets(const TrainOptions& options) {
  for (const DatasetRecipe& d : options.datasets) {
    if (std::filesystem::exists(std::filesystem::path(d.out) / "manifest.json")) continue;
    DatasetOptions g;
    g.scenario = d.scenario;
    g.count = d.count;
    g.seed = d.seed;
    g.frame_rate_hz = d.frame_rate_hz;
    g.hide_outcome_frames = d.hide_outcome_frames;
    g.balance = d.balance;
    g.mesh_density = parse_mesh_density(d.mesh_density, "recipe datasets mesh_density");
    g.out_dir = d.out;
    g.jobs = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    std::printf("generating %lld %s scenes (seed %llu) into %s\n", static_cast<long long>(g.count),
                g.scenario.c_str(), static_cast<unsigned long long>(g.seed), g.out_dir.c_str());
    generate_with_progress(g);
  }
}

void print_summary(const TrainResult& r, const TrainOptions& options) {
  std::printf("trained %lld steps (%lld per epoch, started at %lld), last loss %.5g; wrote %s\n",
              static_cast<long long>(r.steps), static_cast<long long>(r.steps_per_epoch),
              static_cast<long long>(r.start_step), r.last_loss, options.out.c_str());
  for (const EpochReport& e : r.epochs) {
    std::printf("  epoch %3d  step %6lld  train loss %.5g", e.epoch + 1,
                static_cast<long long>(e.step), e.train_loss);
    if (std::isnan(e.val_loss)) {
      std::printf("  (no validation scenes)\n");
    } else {
      std::printf("  val loss %.5g  val rollout error %.4f\n", e.val_loss, e.val_rollout_error);
    }
  }
  if (r.world_size > 1 && !r.losses.empty()) {
    const double n = static_cast<double>(r.losses.size());
    std::printf("  %d ranks: %.3f s per step, of which %.2f ms in the gradient all-reduce\n",
                r.world_size, r.train_seconds / n, 1e3 * r.allreduce_seconds / n);
  }
}

// One rank of a data-parallel job (started by the launcher, torchrun-style env, or srun).
void run_rank(const TrainOptions& options, const DistributedOptions& dist) {
  ProcessGroup group(dist);
  if (group.rank() == 0) {
    std::printf("distributed: %s backend, world size %d, rendezvous %s:%d\n",
                group.backend().c_str(), group.world_size(), dist.master_addr.c_str(),
                dist.master_port);
    std::fflush(stdout);
  }
  const TrainResult r = train_model(options, /*show_progress=*/group.rank() == 0, &group);
  if (group.rank() == 0) print_summary(r, options);
}

void run_train(const TrainArgs& args) {
  const TrainOptions options = build_options(args);
  if (const std::optional<DistributedOptions> dist = DistributedOptions::from_environment()) {
    run_rank(options, *dist);
    return;
  }
  // A recipe of a data-parallel run is repeated with as many ranks unless --nproc says otherwise.
  const int nnodes = args.dist.nnodes;
  const int nproc =
      args.dist.nproc_given() ? args.dist.nproc : std::max(1, options.world_size / nnodes);
  if (!args.recipe.empty() && options.world_size != nproc * nnodes) {
    log_warn("train: the recipe's run had ", options.world_size, " rank(s) (effective batch ",
             static_cast<int64_t>(options.batch) * options.world_size, "); this one has ",
             nproc * nnodes, " (effective batch ",
             static_cast<int64_t>(options.batch) * nproc * nnodes, ")");
  }
  generate_missing_datasets(options);
  if (nproc * nnodes > 1) {
    launch_command_ranks(args.dist, nproc, given(args, "--threads"), options.threads);
    return;
  }
  print_summary(train_model(options, /*show_progress=*/true), options);
}

}  // namespace

void add_train_command(CLI::App& app) {
  auto a = std::make_shared<TrainArgs>();
  CLI::App* cmd = app.add_subcommand(
      "train",
      "Train a dynamics model (Adam, Huber loss on p(t+1), one random frame per scene per draw,\n"
      "random-walk noise on input velocities). Writes CKPT, CKPT.state (for --resume) and\n"
      "CKPT.recipe.json (every resolved option; `--recipe CKPT.recipe.json` repeats the run;\n"
      "its \"progress\" says the steps done, the wall time and sittings summed over resumes).\n"
      "After every epoch's validation the checkpoint with the lowest validation rollout error\n"
      "so far is kept as X.best.pt (model selection on the validation split, never test).\n"
      "A recipe's \"datasets\" list is generated first when a directory has no manifest, so\n"
      "`dynscope train --recipe assets/recipes/NAME.json` reproduces a shipped checkpoint.\n"
      "Defaults follow the paper's supplement by dataset scale (movi-* = kubric: lr 5e-3,\n"
      "15 epochs, each scene sampled 2x per epoch; otherwise physion: lr 1e-3, 30 epochs, 8x).\n"
      "Data-parallel: --nproc N starts N ranks on this machine (c10d TCPStore rendezvous on\n"
      "loopback, Gloo all-reduce of the gradients; each rank trains on --batch examples of a\n"
      "step, so the effective batch is N x --batch). Several machines: the same command on\n"
      "each with --nnodes, --node-rank, --master-addr and --master-port, or one process per\n"
      "rank with the torchrun variables MASTER_ADDR, MASTER_PORT, RANK, WORLD_SIZE set.");
  a->cmd = cmd;
  cmd->add_option("--recipe", a->recipe, "JSON file of options; command-line options override it");
  cmd->add_option("--data", a->data,
                  "Dataset directories written by `dynscope generate` (one or more, one scale)");
  cmd->add_option("--out", a->out, "Checkpoint file to write");
  cmd->add_option("--model", a->model, "pointconv, gnn or flat");
  cmd->add_option("--target", a->target, "acc or vel");
  cmd->add_option("--input", a->input, "points or mesh");
  cmd->add_option("--faces", a->faces, "Mesh input: on (interaction points) or off");
  cmd->add_option("--scale", a->scale,
                  "kubric or physion voxel/radius preset (default: by "
                  "the dataset's scenario)");
  cmd->add_option("--epochs", a->epochs, "Epochs (default by scale)");
  cmd->add_option("--samples-per-scene", a->samples, "Draws per training scene per epoch");
  cmd->add_option("--batch", a->batch, "Scenes per optimiser step (default 1)");
  cmd->add_option("--lr", a->lr, "Adam learning rate (default by scale)");
  cmd->add_option("--lr-schedule", a->lr_schedule,
                  "constant (default) or cosine: decay to 1% of --lr over all epochs");
  cmd->add_option(
      "--noise-std", a->noise_std,
      "Random-walk noise std on input velocities, scene units per frame (default 3e-4)");
  cmd->add_option("--noise-mode", a->noise_mode,
                  "point (default): each point its own noise; object: one draw per object, so "
                  "objects stay rigid as in a rollout with rigid projection; centred: each point "
                  "its own draw less its object's mean, so no object as a whole is displaced");
  cmd->add_option("--huber-delta", a->huber_delta,
                  "Huber loss transition in target-std units (default 1; 1000 makes it a squared "
                  "error for any realistic error, as the paper's loss in scene units is)");
  cmd->add_option("--pushforward", a->pushforward,
                  "Most frames the model pushes an example forward before its loss (default 0): "
                  "n from 0 to N is drawn per example, the model predicts n steps without "
                  "gradient from the drawn noisy state as a rollout does, and learns the next "
                  "step from the state it reached itself");
  cmd->add_option("--threads", a->threads, "LibTorch threads (0: default)");
  cmd->add_flag("--resume", a->resume, "Continue from --out and its .state file exactly");
  cmd->add_option("--log", a->log, "CSV log, one row per step");
  cmd->add_flag("--keep-epochs", a->keep_epochs,
                "Also keep each epoch's checkpoint as X.epochNN.pt (with its recipe), to choose "
                "among them later on a validation set");
  cmd->add_option("--checkpoint-every", a->checkpoint_every, "Save every N steps (default 200)");
  cmd->add_option("--max-steps", a->max_steps, "Stop after N steps in total (0: all epochs)");
  cmd->add_option("--seed", a->seed,
                  "Seed of scene order, frames and noise, and of initialisation unless "
                  "--init-seed")
      ->check(unsigned_integer());
  cmd->add_option("--init-seed", a->init_seed,
                  "Seed of the initial weights alone (default: --seed), to tell what the "
                  "initialisation does from what the scene order, frames and noise do")
      ->check(unsigned_integer());
  cmd->add_option("--width", a->width, "Base channel width C (default 32)");
  cmd->add_option("--levels", a->levels, "Hierarchy levels (default 4)");
  cmd->add_option("--bottleneck-blocks", a->bottleneck, "Blocks at the coarsest level (default 3)");
  cmd->add_option("--stem-blocks", a->stem, "Blocks at level 0 before downsampling (default 0)");
  cmd->add_flag("--hold-static", a->hold_static,
                "Static bodies (mass 0: tables, ramps, zones) are given, not predicted: their "
                "points stay inputs but are left out of the loss (each scene's loss is the mean "
                "over its moving points) and held where they are in every rollout of the model");
  cmd->add_flag("--relational-top-only", a->relational_top_only,
                "Relational units at level 0 only, none between downsampled objects (the "
                "paper's U-Net for meshes; mesh input always is so). With --input mesh "
                "--faces off this is the paper's mesh model without face reasoning");
  cmd->add_option("--k", a->k, "Neighbours per conv (default 16)");
  cmd->add_option("--c-mid", a->c_mid, "WeightNet output width (default 16)");
  cmd->add_option("--voxel", a->voxel, "Level-1 voxel (default by scale)");
  cmd->add_option("--radius", a->radius, "Level-0 relational radius (default by scale)");
  cmd->add_option("--sample-voxel", a->sample_voxel,
                  "Initial point sampling voxel (default 0.2 for movi-*, 0.05 otherwise)");
  cmd->add_option("--val-scenes", a->val_scenes, "Validation scenes per epoch (default 4)");
  cmd->add_option("--val-frames", a->val_frames, "Frames of the validation rollout (default 8)");
  add_distributed_options(cmd, a->dist, "training");
  cmd->callback([a] { run_train(*a); });
}

}  // namespace dynscope::app
