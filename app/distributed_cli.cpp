// Data-parallel command-line options and rank launch.
#include "app/distributed_cli.h"

#include <algorithm>
#include <vector>

#include "app/cli_util.h"
#include "engine/core/error.h"
#include "engine/core/log.h"
#include "engine/core/threads.h"
#include "engine/train/launcher.h"

namespace dynscope::app {
namespace {

// The launcher's own options, not passed on to the ranks.
const char* const kLauncherOptions[] = {"--nproc", "--nnodes", "--node-rank", "--master-addr",
                                        "--master-port"};

std::vector<std::string> rank_arguments(bool threads_given, int threads) {
  const std::vector<std::string>& line = command_line();
  std::vector<std::string> out;
  for (size_t i = 1; i < line.size(); ++i) {
    bool skip = false;
    for (const char* name : kLauncherOptions) {
      const std::string n = name;
      if (line[i] == n) {
        skip = true;
        ++i;  // and its value
      } else if (line[i].rfind(n + "=", 0) == 0) {
        skip = true;
      }
      if (skip) break;
    }
    if (!skip) out.push_back(line[i]);
  }
  if (!threads_given) {
    out.push_back("--threads");
    out.push_back(std::to_string(threads));
  }
  return out;
}

}  // namespace

void add_distributed_options(CLI::App* cmd, DistributedArgs& a, const std::string& what) {
  a.cmd = cmd;
  cmd->add_option("--nproc", a.nproc, "Data-parallel ranks of the " + what + " on this machine")
      ->check(CLI::Range(1, 1024));
  cmd->add_option("--nnodes", a.nnodes, "Machines in a data-parallel job (default 1)")
      ->check(CLI::Range(1, 65536));
  cmd->add_option("--node-rank", a.node_rank, "This machine's index in [0, --nnodes)")
      ->check(CLI::Range(0, 65535));
  cmd->add_option("--master-addr", a.master_addr,
                  "Address of the machine of rank 0 (rendezvous; default 127.0.0.1)");
  cmd->add_option("--master-port", a.master_port,
                  "Rendezvous port (default: a free one; needed with several machines)")
      ->check(CLI::Range(0, 65535));
  cmd->add_option("--dist-timeout", a.timeout_s,
                  "Seconds a rank waits for the others (rendezvous and every collective) before "
                  "the job fails (default 120)")
      ->check(CLI::Range(1, 86400));
}

void launch_command_ranks(const DistributedArgs& args, int nproc, bool threads_given, int threads) {
  const int cores = available_cores();
  if (!threads_given) threads = std::max(1, cores / nproc);
  if (nproc * threads > cores) {
    log_warn(nproc, " ranks x ", threads, " threads on ", cores,
             " cores oversubscribe them (slower, and it collapses under a busy neighbour)");
  }
  LaunchOptions launch;
  launch.executable = "/proc/self/exe";
  launch.args = rank_arguments(threads_given, threads);
  launch.nproc = nproc;
  launch.nnodes = args.nnodes;
  launch.node_rank = args.node_rank;
  launch.master_addr = args.master_addr;
  launch.master_port = args.master_port;
  launch.env = {"DYNSCOPE_DIST_TIMEOUT_S=" + std::to_string(args.timeout_s)};
  const LaunchResult result = launch_ranks(launch);
  if (!result.ok()) throw Error("data-parallel job failed: " + result.failure());
}

}  // namespace dynscope::app
