// Helpers shared by the training tests: a tiny generated dataset, a tiny model's options and
// checkpoint comparison.
#pragma once

#include <gtest/gtest.h>
#include <torch/torch.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include "engine/model/checkpoint.h"
#include "engine/sim/dataset.h"
#include "engine/train/train_options.h"

namespace dynscope::testing {

/// `count` scenes of `scenario` generated with `seed` into a temporary directory named after
/// `tag` and this process (8 : 1 : 1 train/val/test split).
inline std::string generate_tiny_dataset(const std::string& tag, const std::string& scenario,
                                         int count, uint64_t seed) {
  const std::filesystem::path d = std::filesystem::temp_directory_path() /
                                  ("dynscope_" + tag + "_data_" + std::to_string(getpid()));
  std::filesystem::remove_all(d);
  DatasetOptions o;
  o.scenario = scenario;
  o.count = count;
  o.seed = seed;
  o.out_dir = d.string();
  generate_dataset(o);
  return d.string();
}

/// A two-level model of width 8 on `data`, one thread, 0.1 sampling voxel, one validation scene.
inline TrainOptions tiny_train_options(const std::string& data, const std::string& out) {
  TrainOptions o;
  o.data_dirs = {data};
  o.out = out;
  o.model.width = 8;
  o.model.levels = 2;
  o.model.bottleneck_blocks = 1;
  o.model.k = 6;
  o.model.k_relational = 6;
  o.model.c_mid = 4;
  o.model.pos_channels = 4;
  o.sampling.voxel = 0.1;
  o.val_scenes = 1;
  o.val_frames = 5;
  o.threads = 1;
  o.checkpoint_every = 1000;
  return o;
}

/// Every parameter of the two checkpoints is bit-equal.
inline void expect_same_weights(const std::string& a, const std::string& b) {
  DynamicsModel ma = load_checkpoint(a);
  DynamicsModel mb = load_checkpoint(b);
  const auto pa = ma->named_parameters();
  const auto pb = mb->named_parameters();
  ASSERT_EQ(pa.size(), pb.size());
  for (const auto& item : pa) {
    EXPECT_TRUE(torch::equal(item.value(), pb[item.key()])) << item.key();
  }
}

}  // namespace dynscope::testing
