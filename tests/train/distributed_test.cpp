// Data-parallel training on c10d (Gloo over loopback), two ranks as two threads of this process:
// identical parameters on every rank, the loss curve of one process with the same effective
// batch, exact resume, and clear errors when a rank is missing.
#include <gtest/gtest.h>
#include <torch/torch.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <exception>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <thread>

#include "engine/core/error.h"
#include "engine/model/checkpoint.h"
#include "engine/sim/dataset.h"
#include "engine/train/launcher.h"
#include "engine/train/process_group.h"
#include "engine/train/trainer.h"
#include "tests/train/train_fixtures.h"

namespace dynscope {
namespace {

namespace fs = std::filesystem;

// 6 drop scenes (4 train, 1 val, 1 test), generated once per test process.
const std::string& dataset_dir() {
  static const std::string dir = testing::generate_tiny_dataset("distributed_test", "drop", 6, 9);
  return dir;
}

fs::path temp_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() /
                     ("dynscope_distributed_test_" + name + "_" + std::to_string(getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

TrainOptions tiny_options(const std::string& out) {
  TrainOptions o = testing::tiny_train_options(dataset_dir(), out);
  o.seed = 3;
  o.samples_per_scene = 3;  // 12 draws per epoch: the last step of an epoch is short
  return o;
}

DistributedOptions rank_options(int rank, int world, int port) {
  DistributedOptions d;
  d.rank = rank;
  d.world_size = world;
  d.master_port = port;
  d.timeout = std::chrono::seconds(30);
  return d;
}

// Runs `body(rank)` for ranks 0..world−1 on threads; rethrows the first failure.
void on_ranks(int world, const std::function<void(int)>& body) {
  std::vector<std::exception_ptr> errors(static_cast<size_t>(world));
  std::vector<std::thread> threads;
  for (int r = 0; r < world; ++r) {
    threads.emplace_back([&, r] {
      try {
        body(r);
      } catch (...) {
        errors[static_cast<size_t>(r)] = std::current_exception();
      }
    });
  }
  for (std::thread& t : threads) t.join();
  for (const std::exception_ptr& e : errors) {
    if (e) std::rethrow_exception(e);
  }
}

// Two ranks train `options` (batch per rank) and return their results.
std::vector<TrainResult> train_two_ranks(const TrainOptions& options) {
  const int port = free_local_port();
  std::vector<TrainResult> results(2);
  on_ranks(2, [&](int r) {
    ProcessGroup group(rank_options(r, 2, port));
    results[static_cast<size_t>(r)] = train_model(options, false, &group);
  });
  return results;
}

TEST(DistributedTraining, TwoRanksStayBitIdenticalAndFollowOneProcessOfTheEffectiveBatch) {
  const fs::path dir = temp_dir("identical");
  TrainOptions dp = tiny_options((dir / "dp.pt").string());
  dp.batch = 1;
  dp.max_steps = 20;
  const std::vector<TrainResult> ranks = train_two_ranks(dp);
  ASSERT_EQ(ranks[0].steps, 20);
  ASSERT_EQ(ranks[1].steps, 20);
  EXPECT_EQ(ranks[0].world_size, 2);
  EXPECT_EQ(ranks[0].steps_per_epoch, 6) << "12 draws, 2 per step over the ranks";
  EXPECT_EQ(ranks[0].parameter_digest, ranks[1].parameter_digest);
  EXPECT_EQ(ranks[0].losses, ranks[1].losses) << "the loss is all-reduced: one curve";
  EXPECT_GT(ranks[0].allreduce_seconds, 0.0);
  // Rank 0 alone wrote the checkpoint; it holds the ranks' parameters.
  DynamicsModel saved = load_checkpoint(dp.out);
  EXPECT_TRUE(fs::exists(recipe_path(dp.out)));
  const TrainOptions recipe = TrainOptions::from_json(
      [&] {
        std::ifstream in(recipe_path(dp.out));
        return std::string(std::istreambuf_iterator<char>(in), {});
      }(),
      recipe_path(dp.out));
  EXPECT_EQ(recipe.world_size, 2);
  EXPECT_EQ(recipe.batch, 1);

  // One process with batch 2 draws the same examples: the same loss curve.
  TrainOptions single = tiny_options((dir / "single.pt").string());
  single.batch = 2;
  single.max_steps = 20;
  const TrainResult one = train_model(single);
  ASSERT_EQ(one.losses.size(), ranks[0].losses.size());
  for (size_t s = 0; s < one.losses.size(); ++s) {
    EXPECT_NEAR(ranks[0].losses[s], one.losses[s], 1e-5 * std::abs(one.losses[s]))
        << "step " << s + 1;
  }
  // (Parameters agree less tightly: Adam's first steps move every weight by about lr whatever
  // the size of its gradient, so float rounding in a near-zero gradient flips a step.)
  EXPECT_GT(saved->parameters().size(), 0u);
}

TEST(DistributedTraining, ResumeContinuesEveryRankExactly) {
  const fs::path dir = temp_dir("resume");
  TrainOptions straight = tiny_options((dir / "straight.pt").string());
  straight.max_steps = 10;
  const std::vector<TrainResult> uninterrupted = train_two_ranks(straight);

  TrainOptions first = tiny_options((dir / "resumed.pt").string());
  first.max_steps = 4;
  train_two_ranks(first);
  TrainOptions second = first;
  second.max_steps = 10;
  second.resume = true;
  const std::vector<TrainResult> resumed = train_two_ranks(second);
  EXPECT_EQ(resumed[0].start_step, 4);
  EXPECT_EQ(resumed[1].start_step, 4);
  EXPECT_EQ(resumed[0].parameter_digest, uninterrupted[0].parameter_digest);
  EXPECT_EQ(resumed[1].parameter_digest, uninterrupted[1].parameter_digest);
  // A state of two ranks resumed by one process is refused, naming the world size.
  TrainOptions alone = second;
  alone.max_steps = 12;
  try {
    train_model(alone);
    FAIL() << "resumed a 2-rank state in one process";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("--nproc 2"), std::string::npos) << e.what();
  }
}

TEST(DistributedTraining, AMissingRankEndsTheRendezvousWithinTheTimeout) {
  DistributedOptions o = rank_options(0, 2, free_local_port());
  o.timeout = std::chrono::seconds(2);
  const auto start = std::chrono::steady_clock::now();
  try {
    ProcessGroup group(o);
    FAIL() << "a group of 2 formed with one rank";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("rendezvous"), std::string::npos) << what;
    EXPECT_NE(what.find("rank 0 of 2"), std::string::npos) << what;
  }
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_LT(s, 15.0);
}

TEST(DistributedTraining, OptionsFromTheTorchrunEnvironment) {
  ::unsetenv("WORLD_SIZE");
  EXPECT_FALSE(DistributedOptions::from_environment().has_value());
  ::setenv("WORLD_SIZE", "4", 1);
  ::setenv("RANK", "3", 1);
  ::setenv("MASTER_ADDR", "10.0.0.7", 1);
  ::setenv("MASTER_PORT", "29511", 1);
  ::unsetenv("LOCAL_RANK");
  const std::optional<DistributedOptions> o = DistributedOptions::from_environment();
  ASSERT_TRUE(o.has_value());
  EXPECT_EQ(o->world_size, 4);
  EXPECT_EQ(o->rank, 3);
  EXPECT_EQ(o->local_rank, 3);
  EXPECT_EQ(o->master_addr, "10.0.0.7");
  EXPECT_EQ(o->master_port, 29511);
  ::setenv("RANK", "4", 1);
  EXPECT_THROW(DistributedOptions::from_environment(), ValueError);
  ::setenv("RANK", "x", 1);
  EXPECT_THROW(DistributedOptions::from_environment(), ValueError);
  for (const char* v : {"WORLD_SIZE", "RANK", "MASTER_ADDR", "MASTER_PORT"}) ::unsetenv(v);
  DistributedOptions nccl;
  nccl.backend = "nccl";
  if (!nccl_available()) {
    EXPECT_THROW(nccl.validate(), ValueError);
  }
}

TEST(DistributedLauncher, AFailingRankStopsTheOthersAndIsNamed) {
  LaunchOptions o;
  o.executable = "/bin/sh";
  o.args = {"-c", "if [ \"$RANK\" = 1 ]; then exit 3; fi; sleep 30"};
  o.nproc = 3;
  o.grace = std::chrono::milliseconds(500);
  const auto start = std::chrono::steady_clock::now();
  const LaunchResult r = launch_ranks(o);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_LT(s, 10.0) << "the sleeping ranks were stopped";
  EXPECT_FALSE(r.ok());
  EXPECT_EQ(r.failed_rank, 1);
  ASSERT_EQ(r.ranks.size(), 3u);
  EXPECT_EQ(r.ranks[1].code, 3);
  EXPECT_TRUE(r.ranks[0].stopped_by_launcher);
  EXPECT_NE(r.failure().find("rank 1"), std::string::npos) << r.failure();

  o.args = {"-c",
            "test \"$WORLD_SIZE\" = 2 && test \"$LOCAL_RANK\" = \"$RANK\" && "
            "test -n \"$MASTER_PORT\""};
  o.nproc = 2;
  EXPECT_TRUE(launch_ranks(o).ok());
  o.nproc = 0;
  EXPECT_THROW(launch_ranks(o), ValueError);
}

}  // namespace
}  // namespace dynscope
