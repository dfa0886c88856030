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

}  // namespace
}  // namespace dynscope
