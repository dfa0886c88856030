// Tests of assets/recipes/run.sh, the script that starts or continues campaign recipes in
// sittings: it must find each recipe's own checkpoint (the top-level "out", not a dataset's),
// start a new run, resume one with a training state, leave a finished one alone and refuse a
// recipe without a checkpoint path. And of assets/recipes/physion-600/evaluate.sh, which
// evaluates the Physion-like campaign's finished runs: held-out set generated when missing, only
// finished runs evaluated, on the right scenes, then compared over seeds; and of
// assets/recipes/movi-a-3k/evaluate.sh, whose groups share runs that must be evaluated once.
// `dynscope` is replaced by a script that records its arguments.
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
const std::string kPhysionEvaluate =
    std::string(DYNSCOPE_SOURCE_DIR) + "/assets/recipes/physion-600/evaluate.sh";
const std::string kMoviEvaluate =
    std::string(DYNSCOPE_SOURCE_DIR) + "/assets/recipes/movi-a-3k/evaluate.sh";
const char* const kScenarios[] = {"drop",    "collide", "roll", "dominoes",
                                  "support", "contain", "link"};

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
    // Like the program, it writes the file a `--json` option names (so that a script that skips
    // evaluations already made sees them).
    write_file(recorder_, "#!/bin/sh\necho \"$@\" >> " + calls_.string() +
                              "\nprev=\nfor a in \"$@\"; do\n"
                              "  if [ \"$prev\" = --json ]; then echo '{}' > \"$a\"; fi\n"
                              "  prev=$a\ndone\n");
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

// A run's progress record, as training writes it into CKPT.recipe.json.
void write_progress(const fs::path& checkpoint, int steps, int total) {
  write_file(checkpoint.string() + ".recipe.json",
             "{\n  \"progress\": {\n    \"steps\": " + std::to_string(steps) +
                 ",\n    \"total_steps\": " + std::to_string(total) + "\n  }\n}\n");
}

class PhysionEvaluateScript : public CampaignScript {
 protected:
  test::CommandResult evaluate(const std::string& split, const std::string& env = "") const {
    return run_shell(env + "DYNSCOPE=" + recorder_.string() +
                     " DYNSCOPE_CAMPAIGN_RUNS=" + (dir_ / "runs").string() +
                     " DYNSCOPE_CAMPAIGN_DATA=" + (dir_ / "data").string() +
                     " DYNSCOPE_CAMPAIGN_OUT=" + (dir_ / "out").string() + " bash " +
                     kPhysionEvaluate + " " + split);
  }
};

TEST_F(PhysionEvaluateScript, GeneratesTheHeldOutSetAndEvaluatesOnlyFinishedRuns) {
  fs::create_directories(dir_ / "runs");
  write_progress(dir_ / "runs" / "centred_s1.pt", 10, 10);
  write_progress(dir_ / "runs" / "centred_s2.pt", 10, 10);
  write_progress(dir_ / "runs" / "paper_s3.pt", 5, 10);
  const auto result = evaluate("test");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const std::string data = (dir_ / "data" / "physion-test").string();
  const std::string out = (dir_ / "out").string();
  std::string expected;
  for (const char* s : kScenarios) {
    expected += "generate --scenario " + std::string(s) + " --count 24 --seed 3 --out " + data +
                "/" + s + " --jobs 2\n";
  }
  std::string scenes;
  for (const char* s : kScenarios) scenes += " --data " + data + "/" + s;
  for (const char* name : {"centred_s1", "centred_s2"}) {
    expected += "eval --checkpoint " + (dir_ / "runs").string() + "/" + name + ".best.pt" + scenes +
                " --split all --threads 1 --json " + out + "/" + name + ".test.json\n";
  }
  expected += "compare centred=" + out + "/centred_s1.test.json," + out +
              "/centred_s2.test.json --json " + out + "/compare.test.json\n";
  EXPECT_EQ(calls(), expected);
  EXPECT_NE(result.output.find("paper_s3: still training (5 of 10 steps), skipped"),
            std::string::npos)
      << result.output;
}

// `hidden`: the paper's protocol on the scenes its window does not give away, generated apart.
TEST_F(PhysionEvaluateScript, HiddenGeneratesSelectedScenesAndEvaluatesWithThePapersProtocol) {
  fs::create_directories(dir_ / "runs");
  write_progress(dir_ / "runs" / "paper_s2.pt", 10, 10);
  const auto result = evaluate("hidden");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const std::string data = (dir_ / "data" / "physion-hidden").string();
  const std::string out = (dir_ / "out").string();
  std::string expected;
  for (const char* s : kScenarios) {
    expected += "generate --scenario " + std::string(s) +
                " --count 48 --seed 4 --hide-outcome 14 --balance --out " + data + "/" + s +
                " --jobs 2\n";
  }
  std::string scenes;
  for (const char* s : kScenarios) scenes += " --data " + data + "/" + s;
  expected += "eval --checkpoint " + (dir_ / "runs").string() + "/paper_s2.best.pt" + scenes +
              " --split all --observed 14 --threshold-fraction 1.5 --scenario-threshold-fraction "
              "drop=1 --scenario-threshold-fraction contain=1 --threads 1 --json " +
              out + "/paper_s2.hidden.json\n";
  expected +=
      "compare paper=" + out + "/paper_s2.hidden.json --json " + out + "/compare.hidden.json\n";
  EXPECT_EQ(calls(), expected);
}

TEST_F(PhysionEvaluateScript, ValidationNeedsTheCampaignsDataUnknownSplitsAreRefusedHelpExplains) {
  const auto val = evaluate("val");
  EXPECT_NE(val.exit_code, 0) << val.output;
  EXPECT_NE(val.output.find("a campaign recipe's first run writes it"), std::string::npos)
      << val.output;
  const auto bad = evaluate("train");
  EXPECT_NE(bad.exit_code, 0) << bad.output;
  EXPECT_NE(bad.output.find("usage:"), std::string::npos) << bad.output;
  const auto help = evaluate("--help");
  EXPECT_EQ(help.exit_code, 0) << help.output;
  EXPECT_NE(help.output.find("the held-out set, 24 scenes per scenario"), std::string::npos)
      << help.output;
  EXPECT_EQ(calls(), "") << "nothing is run";
}

TEST_F(PhysionEvaluateScript, EvaluatesTheValidationSplitOfTheCampaignsData) {
  for (const char* s : kScenarios) {
    fs::create_directories(dir_ / "data" / "physion-600" / s);
    write_file(dir_ / "data" / "physion-600" / s / "manifest.json", "{}");
  }
  fs::create_directories(dir_ / "runs");
  write_progress(dir_ / "runs" / "paper_s1.pt", 10, 10);
  const auto result = evaluate("val");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const std::string c = calls();
  EXPECT_EQ(c.find("generate"), std::string::npos) << c;
  EXPECT_NE(c.find("eval --checkpoint " + (dir_ / "runs").string() + "/paper_s1.best.pt --data " +
                   (dir_ / "data" / "physion-600" / "drop").string()),
            std::string::npos)
      << c;
  EXPECT_NE(
      c.find(" --split val --threads 1 --json " + (dir_ / "out").string() + "/paper_s1.val.json\n"),
      std::string::npos)
      << c;
  EXPECT_NE(c.find("compare paper=" + (dir_ / "out").string() + "/paper_s1.val.json"),
            std::string::npos)
      << c;
}

// DYNSCOPE_CAMPAIGN_EPOCH=last (movi-a's `evaluate.sh SPLIT last`): the same finished runs, read at
// their last epoch (NAME.pt) into files of their own, so that both readings sit side by side.
TEST_F(PhysionEvaluateScript, ReadsTheLastEpochsIntoFilesOfTheirOwnWhenAsked) {
  fs::create_directories(dir_ / "runs");
  write_progress(dir_ / "runs" / "centred_s1.pt", 10, 10);
  write_progress(dir_ / "runs" / "paper_s3.pt", 5, 10);
  const std::string out = (dir_ / "out").string();
  fs::create_directories(out);
  write_file(out + "/centred_s1.test.json", "{}");  // the best epoch's reading, already made
  const auto result = evaluate("test", "DYNSCOPE_CAMPAIGN_EPOCH=last ");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const std::string c = calls();
  EXPECT_NE(c.find("eval --checkpoint " + (dir_ / "runs").string() + "/centred_s1.pt --data"),
            std::string::npos)
      << c;
  EXPECT_NE(c.find(" --threads 1 --json " + out + "/centred_s1.last.test.json\n"),
            std::string::npos)
      << c;
  EXPECT_EQ(c.find(".best.pt"), std::string::npos) << c;
  EXPECT_EQ(c.find("paper_s3"), std::string::npos) << "a run still training is not read: " << c;
  EXPECT_NE(c.find("compare centred=" + out + "/centred_s1.last.test.json --json " + out +
                   "/compare.last.test.json\n"),
            std::string::npos)
      << c;
  EXPECT_TRUE(fs::exists(out + "/centred_s1.last.test.txt"));

  const auto bad = evaluate("test", "DYNSCOPE_CAMPAIGN_EPOCH=middle ");
  EXPECT_NE(bad.exit_code, 0) << bad.output;
  EXPECT_NE(bad.output.find("DYNSCOPE_CAMPAIGN_EPOCH must be best or last, not 'middle'"),
            std::string::npos)
      << bad.output;
  EXPECT_EQ(calls().find("eval --checkpoint", c.size()), std::string::npos) << "nothing more read";
}

// The movi-a campaign compares a plain run in two groups (the paper's size, and beside its
// pushforward recipe): it is evaluated once, into the data set's folder, and both groups' compare
// lines read that file; each group's comparison goes into its own folder.
TEST_F(CampaignScript, MoviEvaluatesARunInTwoGroupsOnceAndComparesItInBoth) {
  const fs::path runs = dir_ / "runs";
  fs::create_directories(runs);
  write_progress(runs / "pointconv_acc_r09_c32l4_s1.pt", 10, 10);
  write_progress(runs / "pointconv_acc_r09_pf1_c32l4_s1.pt", 10, 10);
  write_progress(runs / "gnn_acc_r09_pf1_c32l4_s2.pt", 5, 10);
  write_progress(runs / "mesh_faces_on_sparse_c32l4_s1.pt", 10, 10);
  const std::string out = (dir_ / "out").string();
  const auto result =
      run_shell("DYNSCOPE=" + recorder_.string() + " DYNSCOPE_CAMPAIGN_RUNS=" + runs.string() +
                " DYNSCOPE_CAMPAIGN_OUT=" + out + " bash " + kMoviEvaluate + " test");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const std::string evals = out + "/campaign-evals/movi-a-3k";
  const std::string sparse = out + "/campaign-evals/movi-a-3k-sparse";
  const std::string plain = evals + "/pointconv_acc_r09_c32l4_s1.test.json";
  const std::string pf1 = evals + "/pointconv_acc_r09_pf1_c32l4_s1.test.json";
  const std::string faces = sparse + "/mesh_faces_on_sparse_c32l4_s1.test.json";
  const std::string eval_tail = " --data data/movi-a-3k --split test --threads 1 --json ";
  const std::string expected =
      "eval --checkpoint " + runs.string() + "/pointconv_acc_r09_c32l4_s1.best.pt" + eval_tail +
      plain + "\ncompare pointconv_acc_r09_c32l4=" + plain + " --json " + out +
      "/campaign-c32l4/compare.test.json\n" +
      "eval --checkpoint " + runs.string() + "/mesh_faces_on_sparse_c32l4_s1.best.pt" +
      " --data data/movi-a-3k-sparse --split test --threads 1 --json " + faces +
      "\ncompare mesh_faces_on_sparse_c32l4=" + faces + " --json " + out +
      "/campaign-sparse/compare.test.json\n" +
      "eval --checkpoint " + runs.string() + "/pointconv_acc_r09_pf1_c32l4_s1.best.pt" +
      eval_tail + pf1 + "\ncompare pointconv_acc_r09_pf1_c32l4=" + pf1 +
      " pointconv_acc_r09_c32l4=" + plain + " --json " + out + "/campaign-pf1/compare.test.json\n";
  EXPECT_EQ(calls(), expected);
  EXPECT_NE(result.output.find("gnn_acc_r09_pf1_c32l4_s2: still training (5 of 10 steps)"),
            std::string::npos)
      << result.output;
  EXPECT_NE(result.output.find("no finished run to compare"), std::string::npos)
      << "the first budget's group has none: " << result.output;
  EXPECT_TRUE(fs::exists(evals + "/pointconv_acc_r09_c32l4_s1.test.txt"));
  EXPECT_FALSE(fs::exists(out + "/campaign-pf1/pointconv_acc_r09_c32l4_s1.test.json"))
      << "a group's folder holds its comparison only";
}

}  // namespace
}  // namespace dynscope
