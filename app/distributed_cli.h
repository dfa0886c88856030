// The data-parallel options shared by `train` and `eval` (torchrun's: --nproc, --nnodes,
// --node-rank, --master-addr, --master-port) and the launch of a command's ranks.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

namespace dynscope::app {

struct DistributedArgs {
  int nproc = 1;
  int nnodes = 1;
  int node_rank = 0;
  std::string master_addr = "127.0.0.1";
  int master_port = 0;
  int timeout_s = 120;
  const CLI::App* cmd = nullptr;

  bool nproc_given() const { return cmd && cmd->count("--nproc") > 0; }
};

/// Adds the options to `cmd` (`what` names the work in their help, e.g. "training").
void add_distributed_options(CLI::App* cmd, DistributedArgs& args, const std::string& what);

/// Runs this command's `nproc` ranks on this machine (the command line without the launcher's
/// options, plus `--threads T` with the cores shared out when `threads_given` is false) and
/// waits for them. Throws Error naming the rank that failed first.
void launch_command_ranks(const DistributedArgs& args, int nproc, bool threads_given, int threads);

}  // namespace dynscope::app
