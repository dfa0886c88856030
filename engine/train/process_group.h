// Data-parallel process groups on PyTorch's c10d: rendezvous through a TCPStore (rank 0 serves
// it), ProcessGroupGloo on CPU (ProcessGroupNCCL when LibTorch has CUDA and it is asked for), and
// a timeout on the rendezvous and on every collective. The torchrun environment convention
// (MASTER_ADDR, MASTER_PORT, RANK, WORLD_SIZE, LOCAL_RANK) names a rank's place.
#pragma once

#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace dynscope {

/// Where one rank sits in a job and how long it waits for the others.
struct DistributedOptions {
  int rank = 0;
  int world_size = 1;
  int local_rank = 0;  ///< Rank on this machine.
  std::string master_addr = "127.0.0.1";
  int master_port = 29500;
  std::chrono::milliseconds timeout{std::chrono::seconds(120)};
  std::string backend = "gloo";  ///< "gloo" (CPU) or "nccl" (CUDA builds of LibTorch only).

  /// Throws ValueError naming the field (rank outside [0, world_size), port, timeout, backend).
  void validate() const;
  /// The torchrun convention: RANK, WORLD_SIZE, LOCAL_RANK (default RANK), MASTER_ADDR (default
  /// 127.0.0.1), MASTER_PORT (default 29500), DYNSCOPE_DIST_TIMEOUT_S (default 120) and
  /// DYNSCOPE_DIST_BACKEND (default gloo). nullopt when WORLD_SIZE is unset; ValueError naming the
  /// variable when one is malformed.
  static std::optional<DistributedOptions> from_environment();
};

/// True when this LibTorch can run the NCCL backend (built with CUDA and c10d NCCL).
bool nccl_available();

/// One rank's membership of a process group. Every call is collective: all ranks make the same
/// calls in the same order. Throws Error naming the rank and the operation when another rank
/// does not answer within the timeout (died or stalled).
class ProcessGroup {
 public:
  /// Rendezvous: rank 0 serves the store at master_addr:master_port, every rank connects and the
  /// backend connects all ranks. Throws Error when they are not all there within the timeout.
  explicit ProcessGroup(const DistributedOptions& options);
  ~ProcessGroup();
  ProcessGroup(const ProcessGroup&) = delete;
  ProcessGroup& operator=(const ProcessGroup&) = delete;

  int rank() const;
  int world_size() const;
  const DistributedOptions& options() const;
  /// "gloo" or "nccl".
  const std::string& backend() const;

  /// Returns when every rank has called it.
  void barrier(const std::string& what);
  /// Rank 0's `bytes` on every rank (through the store).
  std::string broadcast_bytes(const std::string& what, const std::string& bytes);
  /// Every rank's `bytes` in rank order on rank 0; other ranks get an empty list.
  std::vector<std::string> gather_bytes(const std::string& what, const std::string& bytes);

  struct Impl;
  Impl& impl() { return *impl_; }

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace dynscope
