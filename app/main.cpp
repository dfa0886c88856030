// dynscope: entry point; dispatches to the subcommands and turns errors into one clear line.
#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>

#include "app/cli_util.h"
#include "app/commands.h"
#include "engine/core/log.h"
#include "engine/model/torch_runtime.h"

int main(int argc, char** argv) {
  dynscope::app::set_command_line(argc, argv);
  // One compute-thread budget for LibTorch, OpenBLAS and our loops unless a command's --threads
  // asks for more (engine/core/threads.h says why the default is one thread).
  dynscope::set_torch_threads(0);
  CLI::App app{
      "dynscope: a workbench for learned object dynamics (hierarchical PointConv U-Net).\n"
      "Generate ground truth, train and roll out models, and inspect scenes, rollouts and\n"
      "model internals. Run `dynscope SUBCOMMAND --help` for details."};
  app.require_subcommand(1);
  // Every error is one line, like the errors of the commands themselves.
  app.failure_message([](const CLI::App*, const CLI::Error& e) {
    return std::string("dynscope: error: ") + e.what() + " (see --help)\n";
  });
  app.set_version_flag("--version", "dynscope 0.1.0");
  std::string log_level = "info";
  app.add_option("--log-level", log_level, "debug, info, warn, error or quiet")
      ->capture_default_str();
  app.parse_complete_callback([&] { dynscope::set_log_level(dynscope::parse_log_level(log_level)); });

  dynscope::app::add_info_command(app);
  dynscope::app::add_generate_command(app);
  dynscope::app::add_render_command(app);
  dynscope::app::add_train_command(app);
  dynscope::app::add_rollout_command(app);
  dynscope::app::add_eval_command(app);
  dynscope::app::add_compare_command(app);
  dynscope::app::add_trace_command(app);
  dynscope::app::add_explain_command(app);
  dynscope::app::add_view_command(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::cerr << "dynscope: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
