// A torchrun-style launcher: starts the ranks of this machine as child processes of one
// executable with the rendezvous environment (MASTER_ADDR, MASTER_PORT, RANK, WORLD_SIZE,
// LOCAL_RANK), forwards their output line by line with a rank prefix, and ends the job when one
// rank fails.
#pragma once

#include <chrono>
#include <string>
#include <vector>

namespace dynscope {

struct LaunchOptions {
  std::string executable;         ///< Program every rank runs (e.g. /proc/self/exe).
  std::vector<std::string> args;  ///< Its arguments (argv[1..]).
  int nproc = 2;                  ///< Ranks on this machine.
  int nnodes = 1;                 ///< Machines in the job.
  int node_rank = 0;              ///< This machine's index: its ranks are node_rank·nproc + i.
  std::string master_addr = "127.0.0.1";
  int master_port = 0;  ///< 0: a free port of this machine (single-machine jobs only).
  /// How long the other ranks get to stop (SIGTERM) after one fails before SIGKILL.
  std::chrono::milliseconds grace{std::chrono::seconds(5)};
  /// Extra environment of every rank ("NAME=value").
  std::vector<std::string> env;

  /// Throws ValueError naming the field.
  void validate() const;
};

/// What became of one rank.
struct RankExit {
  int rank = 0;
  int pid = 0;
  int code = 0;                      ///< Exit status, or 128 + signal.
  int signal = 0;                    ///< Signal that ended it (0: exited).
  bool stopped_by_launcher = false;  ///< Ended because another rank failed first.
};

struct LaunchResult {
  std::vector<RankExit> ranks;  ///< This machine's ranks, by local rank.
  int failed_rank = -1;         ///< Global rank that failed first, or -1.
  bool ok() const { return failed_rank < 0; }
  /// "rank 1 (pid 1234) was killed by signal 9" or "" when all succeeded.
  std::string failure() const;
};

/// Starts the ranks and waits for all of them. Lines of a rank's stdout go to stdout and of its
/// stderr to stderr, each prefixed "[rank R] "; the launcher's own lines ("started rank R (pid
/// P)", failures) go to stderr. When a rank exits non-zero or by a signal, the others are sent
/// SIGTERM, then SIGKILL after `grace`. SIGINT/SIGTERM to the launcher are passed to the ranks.
/// Throws ValueError for bad options, Error when a process cannot be started.
LaunchResult launch_ranks(const LaunchOptions& options);

/// A TCP port of the loopback interface that was free a moment ago.
int free_local_port();

}  // namespace dynscope
