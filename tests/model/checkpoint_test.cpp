// Checkpoints: identical outputs after a round trip, clear errors for mismatches and bad files.
#include "engine/model/checkpoint.h"

#include <gtest/gtest.h>
#include <torch/serialize/output-archive.h>
#include <torch/types.h>
#include <torch/utils.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "engine/core/error.h"
#include "tests/model/model_test_util.h"

namespace dynscope {
namespace {

namespace fs = std::filesystem;
using testing::make_scene;
using testing::make_state;
using testing::tiny_config;

class CheckpointTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("dynscope_ckpt_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
            "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
};

DynamicsModel trained_like_model(ModelKind kind) {
  torch::manual_seed(7);
  ModelConfig c = tiny_config(kind);
  c.target = TargetMode::kVelocity;
  DynamicsModel model(c);
  NormStats s;
  s.velocity_mean = Vec3(0.01, 0.02, 0.03);
  s.target_std = Vec3(0.5, 0.25, 2.0);
  s.z_mean = 0.3;
  model->set_stats(s);
  return model;
}

TEST_F(CheckpointTest, SaveLoadGivesIdenticalOutputs) {
  for (ModelKind kind : {ModelKind::kPointConv, ModelKind::kGnn, ModelKind::kFlat}) {
    DynamicsModel model = trained_like_model(kind);
    const std::string file = path("model_" + to_string(kind) + ".pt");
    save_checkpoint(file, model);
    for (const auto& entry : fs::directory_iterator(fs::path(file).parent_path())) {
      EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos)
          << "temporary file left behind: " << entry.path();
    }
    DynamicsModel loaded = load_checkpoint(file);
    EXPECT_EQ(loaded->config().to_json(), model->config().to_json());
    EXPECT_EQ(loaded->stats().target_std, model->stats().target_std);
    const PointState st = make_state(make_scene(3, 50, 1), 2);
    EXPECT_EQ(loaded->predict_next(st), model->predict_next(st)) << to_string(kind);

    const CheckpointInfo info = read_checkpoint_info(file);
    EXPECT_EQ(info.format_version, kCheckpointFormat);
    EXPECT_EQ(info.config.kind, kind);
    EXPECT_EQ(info.parameter_count, parameter_count(*model));
    EXPECT_DOUBLE_EQ(info.stats.z_mean, model->stats().z_mean);
  }
}

TEST_F(CheckpointTest, LoadingIntoAnotherArchitectureNamesTheKey) {
  DynamicsModel model = trained_like_model(ModelKind::kPointConv);
  const std::string file = path("a.pt");
  save_checkpoint(file, model);

  ModelConfig wider = model->config();
  wider.width = 16;
  DynamicsModel other(wider);
  const torch::Tensor before = other->unet->head->parameters()[0].clone();
  try {
    load_checkpoint_weights(file, other);
    FAIL() << "expected an architecture mismatch";
  } catch (const IoError&) {
    FAIL() << "a mismatch is not an I/O error";
  } catch (const Error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("architecture mismatch"), std::string::npos) << msg;
    EXPECT_NE(msg.find("'unet."), std::string::npos) << msg;
    EXPECT_NE(msg.find(file), std::string::npos) << msg;
  }
  EXPECT_TRUE(torch::equal(before, other->unet->head->parameters()[0]));

  ModelConfig deeper = model->config();
  deeper.bottleneck_blocks = 2;
  DynamicsModel more(deeper);
  EXPECT_THROW(load_checkpoint_weights(file, more), Error);
  ModelConfig shallower = model->config();
  shallower.bottleneck_blocks = 0;
  DynamicsModel fewer(shallower);
  try {
    load_checkpoint_weights(file, fewer);
    FAIL() << "expected an architecture mismatch";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("'unet.bottleneck.0."), std::string::npos) << e.what();
  }
}

TEST_F(CheckpointTest, CorruptOrTruncatedFilesAreIoErrors) {
  DynamicsModel model = trained_like_model(ModelKind::kPointConv);
  const std::string good = path("good.pt");
  save_checkpoint(good, model);
  const auto size = fs::file_size(good);

  const std::string truncated = path("truncated.pt");
  fs::copy_file(good, truncated);
  fs::resize_file(truncated, size / 2);
  EXPECT_THROW(load_checkpoint(truncated), IoError);

  const std::string garbage = path("garbage.pt");
  std::ofstream(garbage) << "this is not a checkpoint";
  try {
    load_checkpoint(garbage);
    FAIL() << "expected IoError";
  } catch (const IoError& e) {
    EXPECT_EQ(e.path(), garbage);
  }
  EXPECT_THROW(load_checkpoint(path("missing.pt")), IoError);
  EXPECT_THROW(read_checkpoint_info(garbage), IoError);
}

TEST_F(CheckpointTest, ForeignArchiveIsAFormatError) {
  const std::string foreign = path("foreign.pt");
  torch::serialize::OutputArchive archive;
  archive.write("weight", torch::ones({2}));
  archive.save_to(foreign);
  EXPECT_THROW(load_checkpoint(foreign), FormatError);
}

TEST_F(CheckpointTest, UnwritablePathIsAnIoErrorAndLeavesNoFile) {
  DynamicsModel model = trained_like_model(ModelKind::kPointConv);
  const std::string file = path("no_such_dir/model.pt");
  EXPECT_THROW(save_checkpoint(file, model), IoError);
  EXPECT_FALSE(fs::exists(file));
  // Overwriting keeps a readable file.
  const std::string twice = path("twice.pt");
  save_checkpoint(twice, model);
  save_checkpoint(twice, model);
  EXPECT_NO_THROW(load_checkpoint(twice));
}

}  // namespace
}  // namespace dynscope
