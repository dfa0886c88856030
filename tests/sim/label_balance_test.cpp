// Slow check: over 100 trials every Physion-like scenario has 40-60 % positive outcomes.
#include <gtest/gtest.h>

#include <cstdio>

#include "engine/core/rng.h"
#include "engine/sim/scenario.h"

namespace dynscope {
namespace {

class LabelBalance : public ::testing::TestWithParam<std::string> {};

// The seeds `dynscope generate --seed 0 --count 100` uses.
TEST_P(LabelBalance, FortyToSixtyPercentPositivesOver100Trials) {
  int positives = 0;
  for (uint64_t i = 0; i < 100; ++i) {
    positives += contact_outcome(generate_scene(GetParam(), derive_seed(0, i))) ? 1 : 0;
  }
  std::printf("%s: %d/100 positive\n", GetParam().c_str(), positives);
  EXPECT_GE(positives, 40);
  EXPECT_LE(positives, 60);
}

INSTANTIATE_TEST_SUITE_P(PhysionLike, LabelBalance,
                         ::testing::Values("drop", "collide", "roll", "dominoes", "support",
                                           "contain", "link"));

}  // namespace
}  // namespace dynscope
