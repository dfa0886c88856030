// Dataset manifest reading: splits, labels and clear errors.
#include "engine/rollout/dataset_split.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

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

}  // namespace
}  // namespace dynscope
