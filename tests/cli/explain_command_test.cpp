// `dynscope explain` and `render --explain` as a user runs them: the bundled Physion-like model
// rolled out on the bundled collide scene, explained at its divergence and at a chosen pass.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/support/run_command.h"

namespace dynscope {
namespace {

namespace fs = std::filesystem;
using test::run_dynscope;

const std::string kSource = DYNSCOPE_SOURCE_DIR;
const std::string kCheckpoint = kSource + "/assets/models/physion_pointconv_acc.pt";
const std::string kScene = kSource + "/assets/scenes/collide_0000.h5";

nlohmann::json read_json(const std::string& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

class ExplainCommand : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("dynscope-explain-" + std::to_string(getpid()));
    fs::create_directories(dir_);
    rollout_ = (dir_ / "collide.h5").string();
    const auto r = run_dynscope("rollout --checkpoint " + kCheckpoint + " --scene " + kScene +
                                " --out " + rollout_);
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  static void TearDownTestSuite() {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string explain(const std::string& more) const {
    return "explain --checkpoint " + kCheckpoint + " --rollout " + rollout_ + " " + more;
  }
  static fs::path dir_;
  static std::string rollout_;
};
fs::path ExplainCommand::dir_;
std::string ExplainCommand::rollout_;

TEST_F(ExplainCommand, TheDivergenceIsExplainedWithRankedSharesThatSumToOne) {
  const std::string json = (dir_ / "divergence.json").string();
  const auto r = run_dynscope(explain("--json " + json));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("divergence: pass"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("relational"), std::string::npos) << r.output;
  const nlohmann::json j = read_json(json);
  ASSERT_TRUE(j["frame"].is_number_integer());
  const nlohmann::json& d = j["divergence"];
  EXPECT_EQ(j["frame"], d["frame"]) << "no --frame: the divergence frame is explained";
  EXPECT_EQ(j["object"], d["object"]);
  EXPECT_EQ(j["point"], -1);
  EXPECT_GT(d["threshold"].get<double>(), 0.0);
  EXPECT_GT(j["error"].get<double>(), 0.0);
  EXPECT_NEAR(j["error_growth"].get<double>(), d["growth"].get<double>(), 1e-12);
  // The collide scene's objects are named from the scene the rollout started from.
  EXPECT_NE(j["object"].get<std::string>().find("cylinder"), std::string::npos);
  ASSERT_FALSE(j["contributors"].empty());
  double sum = 0.0, last = 2.0;
  for (const nlohmann::json& c : j["contributors"]) {
    for (const char* key : {"list", "level", "object", "share"}) {
      EXPECT_TRUE(c.contains(key)) << key;
    }
    const double share = c["share"].get<double>();
    EXPECT_LE(share, last) << "sorted by share, descending";
    last = share;
    sum += share;
  }
  EXPECT_NEAR(sum, 1.0, 1e-9);
  EXPECT_FALSE(d["contacts"].empty()) << "the diverging cylinder touches another object";
}

TEST_F(ExplainCommand, AChosenPassObjectAndPointAreExplained) {
  const std::string json = (dir_ / "chosen.json").string();
  auto r = run_dynscope(explain("--frame 10 --object zone_1 --target acceleration --json " + json));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  nlohmann::json j = read_json(json);
  EXPECT_EQ(j["frame"], 10);
  EXPECT_EQ(j["object"], "zone_1");
  EXPECT_EQ(j["target"], "acceleration");
  r = run_dynscope(explain("--frame 10 --point 3 --json " + json));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  j = read_json(json);
  EXPECT_EQ(j["point"], 3);
  EXPECT_NE(r.output.find("explaining point 3"), std::string::npos) << r.output;
}

TEST_F(ExplainCommand, BadQuestionsAreRefusedWithTheOption) {
  auto refused = [&](const std::string& args, const std::string& part) {
    const auto r = run_dynscope(explain(args));
    EXPECT_NE(r.exit_code, 0) << args;
    EXPECT_NE(r.output.find(part), std::string::npos) << args << ":\n" << r.output;
  };
  refused("--frame 1", "--frame");
  refused("--frame 59", "--frame");
  refused("--object table", "zone_1");
  refused("--object zone_1 --point 2", "--object");
  refused("--point 100000", "--point");
  refused("--target speed", "--target");
  const auto r = run_dynscope("explain --checkpoint " + kCheckpoint + " --rollout " + kScene);
  EXPECT_NE(r.exit_code, 0);
}

TEST_F(ExplainCommand, RenderExplainDrawsTheExplainedPass) {
  const std::string out = (dir_ / "render").string();
  const auto r = run_dynscope("render " + rollout_ + " --checkpoint " + kCheckpoint +
                              " --explain --frames 10 --object zone_1 --no-video --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(fs::exists(fs::path(out) / "frame_0010.png")) << r.output;
  EXPECT_NE(r.output.find("explained: object zone_1, pass 10"), std::string::npos) << r.output;
  auto refused = run_dynscope("render " + rollout_ + " --explain --out " + out);
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_NE(refused.output.find("--checkpoint"), std::string::npos) << refused.output;
  refused =
      run_dynscope("render " + kScene + " --checkpoint " + kCheckpoint + " --explain --out " + out);
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_NE(refused.output.find("scene file"), std::string::npos) << refused.output;
  refused = run_dynscope("render " + rollout_ + " --object zone_1 --out " + out);
  EXPECT_NE(refused.output.find("needs --explain"), std::string::npos) << refused.output;
}

}  // namespace
}  // namespace dynscope
