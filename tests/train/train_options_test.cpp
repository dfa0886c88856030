// Tests of recipe validation: integer fields refuse fractions, signs and overflow, and resolve()
// refuses values outside their range, naming the field and the accepted range.
#include "engine/train/train_options.h"

#include <gtest/gtest.h>

#include <string>

#include "engine/core/error.h"

namespace dynscope {
namespace {

// The message of the FormatError that parsing `recipe` throws ("" if none).
std::string parse_error(const std::string& recipe) {
  try {
    TrainOptions::from_json(recipe, "r.json");
  } catch (const FormatError& e) {
    return e.what();
  }
  return "";
}

// The message of the ValueError that resolving `recipe` for movi-a throws ("" if none).
std::string resolve_error(const std::string& recipe) {
  TrainOptions o = TrainOptions::from_json(recipe, "r.json");
  o.data_dirs = {"data"};
  o.out = "model.pt";
  try {
    o.resolve("movi-a");
  } catch (const ValueError& e) {
    return e.what();
  }
  return "";
}

void expect_has(const std::string& message, const std::string& part) {
  EXPECT_NE(message.find(part), std::string::npos) << "'" << part << "' not in: " << message;
}

TEST(TrainOptions, IntegerFieldsRefuseFractionsSignsAndOverflow) {
  expect_has(parse_error(R"({"model_config": {"levels": 3.7}})"),
             "r.json: model_config.levels: must be an integer in [0, 2147483647], got 3.7");
  expect_has(parse_error(R"({"epochs": 2.5})"), "epochs: must be an integer");
  expect_has(parse_error(R"({"seed": -1})"),
             "seed: must be an integer in [0, 18446744073709551615]");
  expect_has(parse_error(R"({"sampling": {"seed": -3}})"), "sampling.seed");
  expect_has(parse_error(R"({"init_seed": -2})"),
             "init_seed: must be an integer in [0, 18446744073709551615]");
  expect_has(parse_error(R"({"init_seed": "one"})"), "init_seed: wrong type");
  expect_has(parse_error(R"({"batch": 4294967297})"), "batch: must be an integer");
  expect_has(parse_error(R"({"pushforward_steps": -1})"), "pushforward_steps: must be an integer");
  expect_has(parse_error(R"({"datasets": [{"out": "d", "scenario": "drop", "count": 1.5}]})"),
             "datasets[0].count");
  expect_has(parse_error(R"({"model_config": {"width": 0}})"), "width: must be >= 1");
  // Integral values written as floats are fine, and so are float fields.
  EXPECT_EQ(parse_error(R"({"model_config": {"levels": 3.0}, "lr": 0.001, "max_steps": 5})"), "");
  EXPECT_EQ(TrainOptions::from_json(R"({"model_config": {"levels": 3.0}})", "r").model.levels, 3);
}

// The initialisation seed is written only when set (recipes without it keep their text), and
// round-trips up to the largest seed.
TEST(TrainOptions, InitSeedIsOptionalAndRoundTrips) {
  TrainOptions o;
  EXPECT_FALSE(o.init_seed.has_value());
  EXPECT_EQ(o.to_json().find("init_seed"), std::string::npos);
  EXPECT_FALSE(TrainOptions::from_json(o.to_json(), "r.json").init_seed.has_value());
  o.init_seed = 18446744073709551615ull;
  const TrainOptions back = TrainOptions::from_json(o.to_json(), "r.json");
  ASSERT_TRUE(back.init_seed.has_value());
  EXPECT_EQ(*back.init_seed, 18446744073709551615ull);
  EXPECT_EQ(back.to_json(), o.to_json());
  TrainOptions base;
  base.init_seed = 4;
  EXPECT_EQ(TrainOptions::from_json(R"({"seed": 9})", "r.json", base).init_seed, 4u)
      << "a recipe without the field keeps the base's";
}

TEST(TrainOptions, ResolveRefusesValuesOutsideTheirRange) {
  EXPECT_EQ(resolve_error("{}"), "");
  expect_has(resolve_error(R"({"threads": 100000})"),
             "threads: must be a finite number in [0, 1024]");
  expect_has(resolve_error(R"({"lr": 1e300})"), "lr: must be a finite number in (0, 10]");
  expect_has(resolve_error(R"({"batch": 0})"), "batch");
  expect_has(resolve_error(R"({"noise_std": -0.1})"), "noise-std");
  expect_has(resolve_error(R"({"noise_mode": "scene"})"),
             "noise-mode: must be point, object or centred, got 'scene'");
  EXPECT_EQ(resolve_error(R"({"noise_mode": "object"})"), "");
  expect_has(resolve_error(R"({"epochs": 100000000})"),
             "epochs: must be a finite number in [1, 1e+06]");
  expect_has(resolve_error(R"({"sampling": {"voxel": -0.3}})"), "sampling.voxel");
  expect_has(resolve_error(R"({"model_config": {"k": 100000}})"), "model_config.k");
}

TEST(TrainOptions, LearningRateSchedules) {
  TrainOptions o;
  o.lr = 2e-3;
  EXPECT_DOUBLE_EQ(learning_rate_at(o, 0, 100), 2e-3);
  EXPECT_DOUBLE_EQ(learning_rate_at(o, 99, 100), 2e-3);
  o.lr_schedule = "cosine";
  EXPECT_DOUBLE_EQ(learning_rate_at(o, 0, 101), 2e-3);
  EXPECT_NEAR(learning_rate_at(o, 50, 101), 2e-3 * (kCosineFinalFraction + 1.0) / 2.0, 1e-15);
  EXPECT_NEAR(learning_rate_at(o, 100, 101), 2e-3 * kCosineFinalFraction, 1e-15);
  for (int64_t s = 1; s < 101; ++s) {
    EXPECT_LT(learning_rate_at(o, s, 101), learning_rate_at(o, s - 1, 101)) << s;
  }
  EXPECT_DOUBLE_EQ(learning_rate_at(o, 0, 1), 2e-3);
  expect_has(resolve_error(R"({"lr_schedule":"linear"})"),
             "lr-schedule: must be constant or cosine");
  EXPECT_EQ(resolve_error(R"({"lr_schedule":"cosine"})"), "");
  expect_has(parse_error(R"({"progress":3})"), "progress");
}

}  // namespace
}  // namespace dynscope
