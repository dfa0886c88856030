// `dynscope train --nproc 2` and `dynscope eval --nproc 2` through the built binary: the
// launcher's output, a rank killed mid-run ends the job naming it, --resume after the kill
// continues exactly, and a 2-rank evaluation equals a 1-rank one.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <torch/torch.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "engine/model/checkpoint.h"
#include "engine/train/train_options.h"
#include "tests/support/run_command.h"
#include "tests/train/train_fixtures.h"

extern char** environ;

namespace dynscope {
namespace {

namespace fs = std::filesystem;

const char* const kTiny =
    " --width 8 --levels 2 --bottleneck-blocks 1 --k 6 --c-mid 4 --sample-voxel 0.1"
    " --val-scenes 1 --val-frames 5 --samples-per-scene 3 --seed 3 --checkpoint-every 4";

std::string read_file(const fs::path& p) {
  std::ifstream in(p);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// Starts `dynscope args` with stdout and stderr into `log`; returns its pid.
pid_t spawn_dynscope(const std::vector<std::string>& args, const fs::path& log) {
  std::vector<std::string> argv = {DYNSCOPE_BINARY, "--log-level", "info"};
  argv.insert(argv.end(), args.begin(), args.end());
  std::vector<char*> cargv;
  for (std::string& a : argv) cargv.push_back(a.data());
  cargv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, DYNSCOPE_BINARY, &actions, nullptr, cargv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  return rc == 0 ? pid : -1;
}

std::vector<std::string> split_args(const std::string& text) {
  std::istringstream in(text);
  std::vector<std::string> out;
  for (std::string a; in >> a;) out.push_back(a);
  return out;
}

using testing::expect_same_weights;

TEST(DistributedCli, KilledRankEndsTheJobAndResumeContinuesExactly) {
  const fs::path dir =
      fs::temp_directory_path() / ("dynscope_distributed_cli_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string data = (dir / "data").string();
  ASSERT_EQ(test::run_dynscope("--log-level warn generate --scenario drop --count 6 --seed 9 "
                               "--out " +
                               data)
                .exit_code,
            0);
  const std::string common = "train --nproc 2 --data " + data + std::string(kTiny);

  // Uninterrupted: one line names backend and world size, rank output is prefixed, and the ranks
  // end with identical parameters.
  const std::string straight = (dir / "straight.pt").string();
  const test::CommandResult run = test::run_dynscope(common + " --max-steps 40 --out " + straight);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("[rank 0] distributed: gloo backend, world size 2"), std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("parameters identical on all 2 ranks"), std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("started rank 1 (pid"), std::string::npos) << run.output;
  std::ifstream recipe_in(recipe_path(straight));
  const TrainOptions recipe = TrainOptions::from_json(
      std::string(std::istreambuf_iterator<char>(recipe_in), {}), recipe_path(straight));
  EXPECT_EQ(recipe.world_size, 2);

  // Kill rank 1 once the first checkpoint is on disk.
  const std::string killed = (dir / "killed.pt").string();
  const fs::path log = dir / "killed.log";
  const pid_t launcher = spawn_dynscope(
      split_args(common + " --max-steps 100000 --dist-timeout 20 --out " + killed), log);
  ASSERT_GT(launcher, 0);
  const std::regex started("started rank 1 \\(pid ([0-9]+)\\)");
  pid_t rank1 = -1;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (std::chrono::steady_clock::now() < deadline) {
    std::smatch m;
    const std::string text = read_file(log);
    if (rank1 < 0 && std::regex_search(text, m, started)) rank1 = std::stoi(m[1].str());
    if (rank1 > 0 && fs::exists(train_state_path(killed))) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_GT(rank1, 0) << read_file(log);
  ASSERT_TRUE(fs::exists(train_state_path(killed))) << read_file(log);
  ASSERT_EQ(::kill(rank1, SIGKILL), 0);
  const auto killed_at = std::chrono::steady_clock::now();
  int status = 0;
  pid_t done = 0;
  while ((done = ::waitpid(launcher, &status, WNOHANG)) == 0 &&
         std::chrono::steady_clock::now() < killed_at + std::chrono::seconds(60)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (done == 0) {
    ::kill(launcher, SIGKILL);
    ::waitpid(launcher, &status, 0);
    FAIL() << "the job did not end after its rank 1 was killed\n" << read_file(log);
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - killed_at).count();
  EXPECT_LT(seconds, 20.0 + 10.0) << "within the timeout (20 s) and the launcher's grace";
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_NE(WEXITSTATUS(status), 0);
  const std::string text = read_file(log);
  EXPECT_NE(text.find("rank 1 (pid " + std::to_string(rank1) + ") was killed by signal 9"),
            std::string::npos)
      << text;

  // The checkpoint left behind is whole, and --resume continues the run exactly.
  const test::CommandResult resumed =
      test::run_dynscope(common + " --max-steps 40 --resume --out " + killed);
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  expect_same_weights(straight, killed);

  // Evaluation shared over two ranks gives exactly one rank's numbers.
  const std::string one = (dir / "one.json").string(), two = (dir / "two.json").string();
  const std::string eval = "eval --checkpoint " + straight + " --data " + data +
                           " --split all --no-baseline --threads 1 --json ";
  ASSERT_EQ(test::run_dynscope(eval + one).exit_code, 0);
  const test::CommandResult shared = test::run_dynscope(eval + two + " --nproc 2");
  ASSERT_EQ(shared.exit_code, 0) << shared.output;
  EXPECT_EQ(read_file(one), read_file(two));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace dynscope
