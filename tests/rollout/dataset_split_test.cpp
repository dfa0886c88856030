// Dataset manifest reading: splits, labels and clear errors.
#include "engine/rollout/dataset_split.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "engine/core/error.h"

namespace dynscope {
namespace {

namespace fs = std::filesystem;

fs::path make_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("dynscope_split_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

TEST(DatasetSplitTest, ReadsFilesAndOutcomesOfOneSplit) {
  const fs::path dir = make_dir("ok");
  std::ofstream(dir / "a.h5") << "x";
  std::ofstream(dir / "b.h5") << "x";
  std::ofstream(dir / "manifest.json")
      << R"({"scenario":"drop","files":[{"file":"a.h5","outcome":1},{"file":"b.h5","outcome":0}],
            "split":{"train":["a.h5"],"val":[],"test":["b.h5"]}})";
  const DatasetSplit s = read_dataset_split(dir.string(), "test");
  EXPECT_EQ(s.scenario, "drop");
  ASSERT_EQ(s.items.size(), 1u);
  EXPECT_EQ(s.items[0].file, "b.h5");
  EXPECT_EQ(s.items[0].outcome, 0);
  EXPECT_TRUE(read_dataset_split(dir.string(), "val").items.empty());
  const DatasetSplit all = read_dataset_split(dir.string(), "all");
  ASSERT_EQ(all.items.size(), 2u) << "a held-out dataset is evaluated whole";
  EXPECT_EQ(all.items[0].file, "a.h5");
  EXPECT_EQ(all.items[1].outcome, 0);
}

TEST(DatasetSplitTest, BadInputsGiveClearErrors) {
  const fs::path dir = make_dir("bad");
  try {
    read_dataset_split(dir.string(), "training");
    FAIL();
  } catch (const ValueError& e) {
    EXPECT_EQ(e.name(), "split");
  }
  EXPECT_THROW(read_dataset_split(dir.string(), "train"), IoError);  // no manifest
  std::ofstream(dir / "manifest.json") << R"({"scenario":"drop","split":{"train":["gone.h5"]}})";
  try {
    read_dataset_split(dir.string(), "train");
    FAIL();
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("gone.h5"), std::string::npos);
  }
}

TEST(DatasetSplitTest, EvenlySpacedSampleKeepsOrderAndSaysWhatItIs) {
  DatasetSplit s;
  s.split = "train";
  for (int i = 0; i < 10; ++i)
    s.items.push_back({"d/" + std::to_string(i), std::to_string(i), i % 2});
  const DatasetSplit four = evenly_spaced_sample(s, 4);
  ASSERT_EQ(four.items.size(), 4u);
  const char* expected[] = {"0", "2", "5", "7"};  // ⌊i·10/4⌋
  for (size_t i = 0; i < 4; ++i) EXPECT_EQ(four.items[i].file, expected[i]);
  EXPECT_EQ(four.items[1].outcome, 0);
  EXPECT_EQ(four.split, "train, 4 of 10 evenly spaced");
  const DatasetSplit whole = evenly_spaced_sample(s, 10);
  EXPECT_EQ(whole.items.size(), 10u);
  EXPECT_EQ(whole.split, "train") << "a split no larger than the sample is left as it is";
  EXPECT_EQ(evenly_spaced_sample(s, 1).items.at(0).file, "0");
  try {
    evenly_spaced_sample(s, 0);
    FAIL();
  } catch (const ValueError& e) {
    EXPECT_EQ(e.name(), "max_scenes");
  }
}

// A dataset directory of one scenario with `n` scenes "<prefix>_i.h5", the first half train and
// the rest val.
fs::path make_scenario(const std::string& name, const std::string& scenario,
                       const std::string& prefix, int n) {
  const fs::path dir = make_dir(name);
  nlohmann::json m = {{"scenario", scenario}, {"files", nlohmann::json::array()}};
  m["split"] = {{"train", nlohmann::json::array()},
                {"val", nlohmann::json::array()},
                {"test", nlohmann::json::array()}};
  for (int i = 0; i < n; ++i) {
    const std::string file = prefix + "_" + std::to_string(i) + ".h5";
    std::ofstream(dir / file) << "x";
    m["files"].push_back({{"file", file}, {"outcome", i % 2}});
    m["split"][i < n / 2 ? "train" : "val"].push_back(file);
  }
  std::ofstream(dir / "manifest.json") << m.dump();
  return dir;
}

TEST(DatasetSplitTest, SeveralDirectoriesAreOneSplitInOrder) {
  const fs::path drop = make_scenario("multi_drop", "drop", "drop", 8);
  const fs::path roll = make_scenario("multi_roll", "roll", "roll", 4);
  const DatasetSplit one = read_dataset_splits({drop.string()}, "val");
  const DatasetSplit single = read_dataset_split(drop.string(), "val");
  EXPECT_EQ(one.dir, single.dir);
  EXPECT_EQ(one.split, "val");
  EXPECT_EQ(one.scenario, "drop");
  ASSERT_EQ(one.items.size(), single.items.size());
  EXPECT_EQ(read_dataset_splits({drop.string()}, "val", 2).split,
            evenly_spaced_sample(single, 2).split)
      << "one directory: exactly what the single-directory functions give";

  const DatasetSplit both = read_dataset_splits({drop.string(), roll.string()}, "val");
  EXPECT_EQ(both.split, "val");
  EXPECT_EQ(both.scenario, "drop, roll");
  EXPECT_EQ(both.dir, drop.string() + ", " + roll.string());
  ASSERT_EQ(both.items.size(), 6u);
  EXPECT_EQ(both.items[0].file, "drop_4.h5");
  EXPECT_EQ(both.items[4].file, "roll_2.h5");
  EXPECT_EQ(both.items[5].outcome, 1);

  // At most 2 per directory: drop's 4 val scenes sampled to 2, roll's 2 kept.
  const DatasetSplit sampled = read_dataset_splits({drop.string(), roll.string()}, "val", 2);
  ASSERT_EQ(sampled.items.size(), 4u);
  EXPECT_EQ(sampled.items[0].file, "drop_4.h5");
  EXPECT_EQ(sampled.items[1].file, "drop_6.h5");
  EXPECT_EQ(sampled.items[2].file, "roll_2.h5");
  EXPECT_EQ(sampled.split, "val, 4 of 6 evenly spaced per directory");
  EXPECT_EQ(read_dataset_splits({drop.string(), roll.string()}, "val", 4).split, "val");
}

TEST(DatasetSplitTest, SeveralDirectoriesRefuseWhatCannotBeOneEvaluation) {
  const fs::path a = make_scenario("dup_a", "drop", "scene", 4);
  const fs::path b = make_scenario("dup_b", "roll", "scene", 4);
  auto error_of = [](const std::vector<std::string>& dirs, int max_scenes = 0) {
    try {
      read_dataset_splits(dirs, "val", max_scenes);
    } catch (const ValueError& e) {
      return e.name() + ": " + e.what();
    }
    return std::string("no error");
  };
  const std::string same_file = error_of({a.string(), b.string()});
  EXPECT_NE(same_file.find("data: "), std::string::npos) << same_file;
  EXPECT_NE(same_file.find("scene_2.h5"), std::string::npos) << same_file;
  const std::string twice = error_of({a.string(), a.string() + "/"});
  EXPECT_NE(twice.find("named twice"), std::string::npos) << twice;
  EXPECT_NE(error_of({}).find("no dataset directory"), std::string::npos);
  EXPECT_NE(error_of({a.string()}, -1).find("max_scenes"), std::string::npos);
  EXPECT_THROW(read_dataset_splits({a.string(), (a / "missing").string()}, "val"), IoError);
}

}  // namespace
}  // namespace dynscope
