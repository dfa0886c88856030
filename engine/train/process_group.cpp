// c10d process groups: TCPStore rendezvous, Gloo (or NCCL), collectives with timeouts.
#include "engine/train/process_group.h"

#include <c10/util/Exception.h>

#include <torch/csrc/distributed/c10d/PrefixStore.hpp>
#include <torch/csrc/distributed/c10d/ProcessGroupGloo.hpp>
#include <torch/csrc/distributed/c10d/TCPStore.hpp>
#ifdef USE_C10D_NCCL
#include <torch/csrc/distributed/c10d/ProcessGroupNCCL.hpp>
#endif

#include <algorithm>
#include <cstdlib>
#include <limits>
#include <string>

#include "engine/core/error.h"
#include "engine/train/process_group_torch.h"

namespace dynscope {

namespace {

std::string env(const char* name) {
  const char* v = std::getenv(name);
  return v ? std::string(v) : std::string();
}

int env_int(const char* name, int fallback, int lo, int hi) {
  const std::string text = env(name);
  if (text.empty()) return fallback;
  size_t used = 0;
  long value = 0;
  try {
    value = std::stol(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || value < lo || value > hi) {
    throw ValueError(name, "must be an integer in [" + std::to_string(lo) + ", " +
                               std::to_string(hi) + "], got '" + text + "'");
  }
  return static_cast<int>(value);
}

std::string seconds(std::chrono::milliseconds t) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g s", static_cast<double>(t.count()) / 1000.0);
  return text;
}

bool is_loopback(const std::string& addr) {
  return addr == "127.0.0.1" || addr == "localhost" || addr == "::1";
}

}  // namespace

void DistributedOptions::validate() const {
  if (world_size < 1) throw ValueError("world_size", "must be at least 1");
  if (rank < 0 || rank >= world_size) {
    throw ValueError("rank",
                     std::to_string(rank) + " is outside [0, " + std::to_string(world_size) + ")");
  }
  if (local_rank < 0) throw ValueError("local_rank", "must be >= 0");
  if (master_port < 1 || master_port > 65535) {
    throw ValueError("master_port", std::to_string(master_port) + " is outside [1, 65535]");
  }
  if (master_addr.empty()) throw ValueError("master_addr", "is empty");
  if (timeout.count() <= 0) throw ValueError("timeout", "must be positive");
  if (backend != "gloo" && backend != "nccl") {
    throw ValueError("backend", "must be gloo or nccl, got '" + backend + "'");
  }
  if (backend == "nccl" && !nccl_available()) {
    throw ValueError("backend", "nccl needs a LibTorch built with CUDA; this one has none");
  }
}

std::optional<DistributedOptions> DistributedOptions::from_environment() {
  if (env("WORLD_SIZE").empty()) return std::nullopt;
  DistributedOptions o;
  o.world_size = env_int("WORLD_SIZE", 1, 1, 1 << 16);
  o.rank = env_int("RANK", 0, 0, o.world_size - 1);
  o.local_rank = env_int("LOCAL_RANK", o.rank, 0, 1 << 16);
  if (!env("MASTER_ADDR").empty()) o.master_addr = env("MASTER_ADDR");
  o.master_port = env_int("MASTER_PORT", 29500, 1, 65535);
  o.timeout = std::chrono::seconds(env_int("DYNSCOPE_DIST_TIMEOUT_S", 120, 1, 86400));
  if (!env("DYNSCOPE_DIST_BACKEND").empty()) o.backend = env("DYNSCOPE_DIST_BACKEND");
  o.validate();
  return o;
}

bool nccl_available() {
#ifdef USE_C10D_NCCL
  return torch::cuda::is_available();
#else
  return false;
#endif
}

struct ProcessGroup::Impl {
  DistributedOptions options;
  c10::intrusive_ptr<c10d::Store> store;
  c10::intrusive_ptr<c10d::ProcessGroup> group;
  int64_t calls = 0;  ///< Store keys are numbered so no two calls share one.

  std::string key(const std::string& what) {
    return "dynscope/" + std::to_string(calls++) + "/" + what;
  }
  // A backend or store failure as one line naming this rank and what it waited for. The group
  // and store are let go without destruction: a Gloo operation still in flight would block
  // their destructors until its own timeout, and the process ends on this error anyway.
  [[noreturn]] void fail(const std::string& what, const std::string& why) {
    if (group) group.release();
    if (store) store.release();
    throw Error("distributed " + what + " failed on rank " + std::to_string(options.rank) + " of " +
                std::to_string(options.world_size) + " (timeout " + seconds(options.timeout) +
                "): " + why + " (another rank died, stalled or never started)");
  }
  // Gloo reports a lost peer as gloo::IoException and the store as c10d::TimeoutError, both
  // std::runtime_errors, LibTorch's own timeouts as c10::Error.
  void wait(const c10::intrusive_ptr<c10d::Work>& work, const std::string& what) {
    try {
      if (!work->wait(options.timeout)) fail(what, "no answer");
    } catch (const c10::Error& e) {
      fail(what, e.what_without_backtrace());
    } catch (const Error&) {
      throw;
    } catch (const std::exception& e) {
      fail(what, e.what());
    }
  }
};

ProcessGroup::ProcessGroup(const DistributedOptions& options) : impl_(std::make_unique<Impl>()) {
  options.validate();
  impl_->options = options;
  const std::string where = options.master_addr + ":" + std::to_string(options.master_port);
  try {
    c10d::TCPStoreOptions store;
    store.port = static_cast<uint16_t>(options.master_port);
    store.isServer = options.rank == 0;
    store.numWorkers = static_cast<size_t>(options.world_size);
    store.waitWorkers = true;
    store.timeout = options.timeout;
    impl_->store = c10::make_intrusive<c10d::TCPStore>(options.master_addr, store);
  } catch (const c10::Error& e) {
    impl_->fail("rendezvous at " + where, e.what_without_backtrace());
  } catch (const std::exception& e) {
    impl_->fail("rendezvous at " + where, e.what());
  }
  // Every rank checks in; rank 0 names the ones that did not come (the store's server itself
  // does not notice missing workers).
  try {
    impl_->store->set("arrived/" + std::to_string(options.rank), std::vector<uint8_t>{1});
    if (options.rank == 0) {
      const auto deadline = std::chrono::steady_clock::now() + options.timeout;
      std::string missing;
      for (int r = 1; r < options.world_size; ++r) {
        const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
            deadline - std::chrono::steady_clock::now());
        try {
          impl_->store->wait({"arrived/" + std::to_string(r)},
                             std::max(left, std::chrono::milliseconds(1)));
        } catch (const std::exception&) {
          missing += (missing.empty() ? "" : ", ") + std::to_string(r);
        }
      }
      if (!missing.empty()) {
        impl_->fail("rendezvous at " + where, "rank(s) " + missing + " never arrived");
      }
    }
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    impl_->fail("rendezvous at " + where, e.what());
  }
  auto store = c10::make_intrusive<c10d::PrefixStore>("pg", impl_->store);
  try {
    if (options.backend == "nccl") {
#ifdef USE_C10D_NCCL
      auto opts = c10d::ProcessGroupNCCL::Options::create();
      opts->timeout = options.timeout;
      impl_->group = c10::make_intrusive<c10d::ProcessGroupNCCL>(store, options.rank,
                                                                 options.world_size, opts);
#endif
    } else {
      auto opts = c10d::ProcessGroupGloo::Options::create(options.timeout);
      const std::string ifname = env("GLOO_SOCKET_IFNAME");
      if (!ifname.empty()) {
        opts->devices.push_back(c10d::ProcessGroupGloo::createDeviceForInterface(ifname));
      } else if (is_loopback(options.master_addr)) {
        opts->devices.push_back(c10d::ProcessGroupGloo::createDeviceForHostname("127.0.0.1"));
      } else {
        opts->devices.push_back(c10d::ProcessGroupGloo::createDefaultDevice());
      }
      opts->threads = 1;
      impl_->group = c10::make_intrusive<c10d::ProcessGroupGloo>(store, options.rank,
                                                                 options.world_size, opts);
    }
  } catch (const c10::Error& e) {
    impl_->fail("rendezvous at " + where + " (" + options.backend + " connection)",
                e.what_without_backtrace());
  } catch (const std::exception& e) {
    impl_->fail("rendezvous at " + where + " (" + options.backend + " connection)", e.what());
  }
}

ProcessGroup::~ProcessGroup() = default;

int ProcessGroup::rank() const { return impl_->options.rank; }
int ProcessGroup::world_size() const { return impl_->options.world_size; }
const DistributedOptions& ProcessGroup::options() const { return impl_->options; }
const std::string& ProcessGroup::backend() const { return impl_->options.backend; }

void ProcessGroup::barrier(const std::string& what) {
  c10d::BarrierOptions opts;
  opts.timeout = impl_->options.timeout;
  c10::intrusive_ptr<c10d::Work> work;
  try {
    work = impl_->group->barrier(opts);
  } catch (const c10::Error& e) {
    impl_->fail("barrier (" + what + ")", e.what_without_backtrace());
  } catch (const std::exception& e) {
    impl_->fail("barrier (" + what + ")", e.what());
  }
  impl_->wait(work, "barrier (" + what + ")");
}

std::string ProcessGroup::broadcast_bytes(const std::string& what, const std::string& bytes) {
  const std::string key = impl_->key(what);
  try {
    if (rank() == 0) {
      impl_->store->set(key, std::vector<uint8_t>(bytes.begin(), bytes.end()));
      return bytes;
    }
    impl_->store->wait({key}, impl_->options.timeout);
    const std::vector<uint8_t> v = impl_->store->get(key);
    return std::string(v.begin(), v.end());
  } catch (const c10::Error& e) {
    impl_->fail("broadcast of " + what, e.what_without_backtrace());
  } catch (const std::exception& e) {
    impl_->fail("broadcast of " + what, e.what());
  }
}

std::vector<std::string> ProcessGroup::gather_bytes(const std::string& what,
                                                    const std::string& bytes) {
  const std::string key = impl_->key(what);
  std::vector<std::string> out;
  try {
    impl_->store->set(key + "/" + std::to_string(rank()),
                      std::vector<uint8_t>(bytes.begin(), bytes.end()));
    if (rank() != 0) return out;
    for (int r = 0; r < world_size(); ++r) {
      const std::string k = key + "/" + std::to_string(r);
      impl_->store->wait({k}, impl_->options.timeout);
      const std::vector<uint8_t> v = impl_->store->get(k);
      out.emplace_back(v.begin(), v.end());
    }
  } catch (const c10::Error& e) {
    impl_->fail("gather of " + what, e.what_without_backtrace());
  } catch (const std::exception& e) {
    impl_->fail("gather of " + what, e.what());
  }
  return out;
}

namespace {

// Tensors split into buckets of one dtype and at most `bucket_bytes` (a larger tensor is a bucket
// of its own).
std::vector<std::vector<torch::Tensor>> buckets(const std::vector<torch::Tensor>& tensors,
                                                int64_t bucket_bytes) {
  std::vector<std::vector<torch::Tensor>> out;
  std::vector<int64_t> sizes;
  std::vector<c10::ScalarType> types;
  for (const torch::Tensor& t : tensors) {
    if (!t.defined() || t.numel() == 0) continue;
    const int64_t bytes = t.numel() * static_cast<int64_t>(t.element_size());
    size_t b = out.size();
    for (size_t i = 0; i < out.size(); ++i) {
      if (types[i] == t.scalar_type() && sizes[i] + bytes <= bucket_bytes) b = i;
    }
    if (b == out.size()) {
      out.emplace_back();
      sizes.push_back(0);
      types.push_back(t.scalar_type());
    }
    out[b].push_back(t);
    sizes[b] += bytes;
  }
  return out;
}

template <typename Collective>
void bucketed(ProcessGroup& group, const std::vector<torch::Tensor>& tensors, int64_t bucket_bytes,
              const std::string& what, Collective collective) {
  torch::NoGradGuard no_grad;
  for (const std::vector<torch::Tensor>& bucket : buckets(tensors, bucket_bytes)) {
    std::vector<torch::Tensor> flat;
    for (const torch::Tensor& t : bucket) flat.push_back(t.detach().reshape({-1}));
    std::vector<torch::Tensor> io = {torch::cat(flat)};
    c10::intrusive_ptr<c10d::Work> work;
    try {
      work = collective(io);
    } catch (const c10::Error& e) {
      group.impl().fail(what, e.what_without_backtrace());
    } catch (const std::exception& e) {
      group.impl().fail(what, e.what());
    }
    group.impl().wait(work, what);
    int64_t offset = 0;
    for (const torch::Tensor& t : bucket) {
      const int64_t n = t.numel();
      t.detach().copy_(io[0].narrow(0, offset, n).view(t.sizes()));
      offset += n;
    }
  }
}

}  // namespace

void broadcast_tensors(ProcessGroup& group, const std::vector<torch::Tensor>& tensors,
                       const char* what, int64_t bucket_bytes) {
  c10d::BroadcastOptions opts;
  opts.rootRank = 0;
  opts.timeout = group.options().timeout;
  bucketed(group, tensors, bucket_bytes, std::string("broadcast of ") + what,
           [&](std::vector<torch::Tensor>& io) { return group.impl().group->broadcast(io, opts); });
}

void allreduce_sum(ProcessGroup& group, const std::vector<torch::Tensor>& tensors, const char* what,
                   int64_t bucket_bytes) {
  c10d::AllreduceOptions opts;
  opts.reduceOp = c10d::ReduceOp::SUM;
  opts.timeout = group.options().timeout;
  bucketed(group, tensors, bucket_bytes, std::string("all-reduce of ") + what,
           [&](std::vector<torch::Tensor>& io) { return group.impl().group->allreduce(io, opts); });
}

}  // namespace dynscope
