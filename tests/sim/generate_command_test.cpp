// Tests of `dynscope generate` through the built binary: output files, exit codes, messages.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <string>

#include "tests/support/run_command.h"

namespace {

namespace fs = std::filesystem;

using dynscope::test::CommandResult;

CommandResult run(const std::string& args) { return dynscope::test::run_dynscope(args); }

class GenerateCommand : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("dynscope_generate_cli_" + std::to_string(getpid()));
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(GenerateCommand, WritesFilesAndManifest) {
  const fs::path out = dir_ / "out";
  const CommandResult r =
      run("generate --scenario collide --count 3 --seed 2 --jobs 2 --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* f : {"collide_0000.h5", "collide_0001.h5", "collide_0002.h5", "manifest.json"}) {
    EXPECT_TRUE(fs::is_regular_file(out / f)) << f;
  }
  EXPECT_NE(r.output.find("wrote 3 collide scenes"), std::string::npos) << r.output;
}

TEST_F(GenerateCommand, HelpListsEveryOptionAndScenario) {
  const CommandResult r = run("generate --help");
  EXPECT_EQ(r.exit_code, 0);
  for (const char* word :
       {"--scenario", "--count", "--seed", "--out", "--jobs", "--meshes", "movi-a", "drop",
        "collide", "roll", "dominoes", "support", "contain", "link", "manifest.json"}) {
    EXPECT_NE(r.output.find(word), std::string::npos) << word;
  }
}

TEST_F(GenerateCommand, BadArgumentsGiveOneClearErrorAndNonZeroExit) {
  const std::string out = (dir_ / "bad").string();
  struct Case {
    std::string args, expected;
  };
  fs::create_directories(dir_);
  FILE* f = std::fopen((dir_ / "plain_file").c_str(), "w");
  ASSERT_NE(f, nullptr);
  std::fclose(f);
  const Case cases[] = {
      {"generate --scenario warp --count 2 --out " + out, "unknown scenario 'warp' (known: movi-a"},
      {"generate --scenario drop --count 0 --out " + out,
       "count: must be an integer in [1, 10000000], got 0"},
      {"generate --scenario drop --count 2 --jobs 0 --out " + out,
       "jobs: must be an integer in [1, 1024], got 0"},
      {"generate --scenario drop --count 2 --out " + (dir_ / "plain_file" / "x").string(),
       "cannot create output directory"},
  };
  for (const Case& c : cases) {
    const CommandResult r = run(c.args);
    EXPECT_NE(r.exit_code, 0) << c.args;
    EXPECT_NE(r.output.find(c.expected), std::string::npos) << c.args << "\n" << r.output;
    // One line: the error, nothing else.
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  }
  EXPECT_FALSE(fs::exists(out));
}

}  // namespace
