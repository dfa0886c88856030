// Registration functions of the dynscope subcommands (one per *_command.cpp).
#pragma once

namespace CLI {
class App;
}

namespace dynscope::app {

/// `dynscope info FILE`: describe a scene file or a mesh.
void add_info_command(CLI::App& app);
/// `dynscope generate`: write ground-truth scenes with Bullet.
void add_generate_command(CLI::App& app);

/// `dynscope render SCENE.h5 --out DIR`: headless PNG frames, contact sheet, optional MP4.
void add_render_command(CLI::App& app);

/// `dynscope train`: train a dynamics model on a generated dataset.
void add_train_command(CLI::App& app);
/// `dynscope rollout`: roll a checkpoint out on one scene into an HDF5 rollout file.
void add_rollout_command(CLI::App& app);
/// `dynscope eval`: point error and contact accuracy over a dataset split, with a baseline.
void add_eval_command(CLI::App& app);
/// `dynscope compare`: runs' evaluations over seeds, with paired per-scene differences.
void add_compare_command(CLI::App& app);
/// `dynscope trace`: record one forward pass of a checkpoint into an HDF5 trace file.
void add_trace_command(CLI::App& app);
/// `dynscope explain`: divergence and gradient × input attribution of a rollout pass.
void add_explain_command(CLI::App& app);
/// `dynscope view [SCENE.h5]`: the interactive viewer, or a headless UI screenshot.
void add_view_command(CLI::App& app);

}  // namespace dynscope::app
