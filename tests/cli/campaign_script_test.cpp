// Tests of assets/recipes/run.sh, the script that starts or continues campaign recipes in
// sittings: it must find each recipe's own checkpoint (the top-level "out", not a dataset's),
// start a new run, resume one with a training state, leave a finished one alone and refuse a
// recipe without a checkpoint path. `dynscope` is replaced by a script that records its arguments.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "tests/support/read_file.h"
#include "tests/support/run_command.h"

namespace dynscope {
namespace {

namespace fs = std::filesystem;
using test::run_shell;

const std::string kScript = std::string(DYNSCOPE_SOURCE_DIR) + "/assets/recipes/run.sh";

void write_file(const fs::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
}

class CampaignScript : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("dynscope_campaign_script_" + std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    recorder_ = dir_ / "record_arguments.sh";
    calls_ = dir_ / "calls.txt";
    write_file(recorder_, "#!/bin/sh\necho \"$@\" >> " + calls_.string() + "\n");
    fs::permissions(recorder_, fs::perms::owner_all);
  }
  void TearDown() override { fs::remove_all(dir_); }

  /// A recipe as the campaigns write them: a dataset with its own "out" before the checkpoint's.
  fs::path recipe(const std::string& name, const fs::path& checkpoint) const {
    const fs::path path = dir_ / (name + ".json");
    std::string text = "{\n  \"datasets\": [\n    {\n      \"out\": \"" + (dir_ / "data").string() +
                       "\",\n      \"scenario\": \"drop\",\n      \"count\": 6\n    }\n  ],\n";
    if (!checkpoint.empty()) text += "  \"out\": \"" + checkpoint.string() + "\",\n";
    text += "  \"seed\": 1\n}\n";
    write_file(path, text);
    return path;
  }

  test::CommandResult run(const fs::path& recipe_path) const {
    return run_shell("DYNSCOPE=" + recorder_.string() + " bash " + kScript + " " +
                     recipe_path.string());
  }

  std::string calls() const { return test::read_bytes(calls_.string()); }

  fs::path dir_, recorder_, calls_;
};

TEST_F(CampaignScript, StartsANewRunIntoTheRecipesCheckpointDirectory) {
  const fs::path ckpt = dir_ / "runs" / "a.pt";
  const fs::path r = recipe("a", ckpt);
  const auto result = run(r);
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("a: starting"), std::string::npos) << result.output;
  EXPECT_EQ(calls(), "train --recipe " + r.string() + "\n");
  EXPECT_TRUE(fs::is_directory(ckpt.parent_path())) << "the checkpoint's folder is made first";
  EXPECT_FALSE(fs::exists(dir_ / "data")) << "a dataset's \"out\" is not the checkpoint";
}

TEST_F(CampaignScript, ContinuesARunWithATrainingState) {
  const fs::path ckpt = dir_ / "b.pt";
  write_file(ckpt.string() + ".state", "state");
  write_file(ckpt.string() + ".recipe.json",
             "{\n  \"progress\": {\n    \"steps\": 5,\n    \"total_steps\": 10\n  }\n}\n");
  const fs::path r = recipe("b", ckpt);
  const auto result = run(r);
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("b: continuing"), std::string::npos) << result.output;
  EXPECT_EQ(calls(), "train --recipe " + r.string() + " --resume\n");
}

TEST_F(CampaignScript, LeavesAFinishedRunAlone) {
  const fs::path ckpt = dir_ / "c.pt";
  write_file(ckpt.string() + ".recipe.json",
             "{\n  \"progress\": {\n    \"steps\": 10,\n    \"total_steps\": 10\n  }\n}\n");
  const auto result = run(recipe("c", ckpt));
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("c: finished (10 steps)"), std::string::npos) << result.output;
  EXPECT_EQ(calls(), "") << "nothing is trained";
}

TEST_F(CampaignScript, RefusesARecipeWithoutACheckpointPath) {
  const auto result = run(recipe("d", fs::path()));
  EXPECT_NE(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("no \"out\" checkpoint path"), std::string::npos) << result.output;
  EXPECT_EQ(calls(), "");
}

}  // namespace
}  // namespace dynscope
