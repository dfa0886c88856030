// Per-object error curves, the divergence rule and the model's contact pairs on hand-made
// rollouts with known answers.
#include "engine/rollout/divergence.h"

#include <gtest/gtest.h>

#include "engine/core/error.h"
#include "engine/rollout/state_history.h"

namespace dynscope {
namespace {

constexpr int kFrames = 12;

// Three objects (ids 1, 2, 3) of four points each in a row along x with `gap` between them.
// Object 2's prediction leaves the truth slowly from frame 3 and jumps at frame `jump`; object 3's
// error grows by `growth3` per frame from frame 3; object 1 is predicted exactly.
Rollout make_rollout(int jump, double growth3, double gap = 0.02) {
  Rollout r;
  r.dt_s = 0.05;
  r.observed_frames = 3;
  const int n = 12;
  r.rest.resize(n, 3);
  for (int i = 0; i < n; ++i) {
    const int o = i / 4;
    r.rest.row(i) << o * (0.2 + gap) + 0.2 * (i % 2), 0.2 * ((i / 2) % 2), 0.1;
    r.object_ids.push_back(o + 1);
  }
  r.pose_object_ids = {1, 2, 3};
  r.pose_rigid = {1, 1, 1};
  for (int f = 0; f < kFrames; ++f) {
    Points truth = r.rest;
    truth.col(2).array() += 0.001 * f;
    Points predicted = truth;
    if (f >= 3) {
      for (int i = 4; i < 8; ++i) predicted(i, 1) += 0.001 * (f - 2) + (f >= jump ? 0.05 : 0.0);
      for (int i = 8; i < 12; ++i) predicted(i, 0) += growth3 * (f - 2);
    }
    r.truth.push_back(truth);
    r.predicted.push_back(predicted);
    r.poses.emplace_back(3);
    r.point_error.push_back((predicted - truth).rowwise().norm().mean());
  }
  r.validate();
  return r;
}

ModelConfig contact_config() {
  ModelConfig c;
  c.levels = 2;
  c.k = 4;
  c.k_relational = 4;
  c.voxel = 0.3;
  c.radius = 0.1;
  return c;
}

TEST(Divergence, ObjectErrorCurvesAreEachObjectsMeanPointError) {
  const Rollout r = make_rollout(8, 0.002);
  const ObjectErrorCurves c = object_error_curves(r);
  ASSERT_EQ(c.objects, (std::vector<int32_t>{1, 2, 3}));
  ASSERT_EQ(c.errors.size(), 3u);
  EXPECT_EQ(c.row(2), 1);
  EXPECT_EQ(c.row(7), -1);
  for (int f = 0; f < kFrames; ++f) {
    EXPECT_EQ(c.errors[0][static_cast<size_t>(f)], 0.0);
    const double two = f < 3 ? 0.0 : 0.001 * (f - 2) + (f >= 8 ? 0.05 : 0.0);
    EXPECT_NEAR(c.errors[1][static_cast<size_t>(f)], two, 1e-12) << f;
    EXPECT_NEAR(c.errors[2][static_cast<size_t>(f)], f < 3 ? 0.0 : 0.002 * (f - 2), 1e-12);
  }
  EXPECT_NEAR(mean_error_of(r, {4, 5, 6, 7}, 9), c.errors[1][9], 1e-15);
  EXPECT_NEAR(mean_error_of(r, {0, 4}, 9), c.errors[1][9] / 2, 1e-15);
}

TEST(Divergence, TheFirstPassWhoseGrowthExceedsHalfTheLargestIsFound) {
  const Rollout r = make_rollout(8, 0.002);
  const PassRange passes = rollout_passes(r);
  EXPECT_EQ(passes.first, first_rollout_trace_frame(3));
  EXPECT_EQ(passes.last, kFrames - 2);
  const Divergence d = find_divergence(r, contact_config());
  ASSERT_TRUE(d.found());
  // Largest growth: object 2's jump, 0.001 + 0.05, produced by the pass at 7.
  EXPECT_TRUE(d.threshold_derived);
  EXPECT_NEAR(d.threshold, kDerivedThresholdFraction * 0.051, 1e-12);
  EXPECT_NE(d.threshold_rule.find("largest"), std::string::npos);
  EXPECT_EQ(d.frame, 7);
  EXPECT_EQ(d.object, 2);
  EXPECT_NEAR(d.growth, 0.051, 1e-12);
  EXPECT_NEAR(d.error, 0.001 * 6 + 0.05, 1e-12);
  ASSERT_EQ(d.objects.size(), 3u);
  EXPECT_EQ(d.objects[0].object, 2);
  EXPECT_EQ(d.objects[1].frame, -1);  // objects 1 and 3 never grow that fast
  EXPECT_EQ(d.objects[2].frame, -1);
  // Objects 1-2 and 2-3 are 0.02 apart (inside the radius), 1 and 3 are not neighbours.
  ASSERT_EQ(d.contacts.size(), 2u);
  for (const ContactPair& c : d.contacts) {
    EXPECT_LT(c.a, c.b);
    EXPECT_GT(c.edges, 0);
    EXPECT_TRUE((c.a == 1 && c.b == 2) || (c.a == 2 && c.b == 3));
  }
}

TEST(Divergence, AGivenThresholdAndEarlierGrowthChangeTheAnswer) {
  const Rollout r = make_rollout(8, 0.002);
  DivergenceOptions o;
  o.threshold = 0.0015;  // object 3 grows 0.002 per frame from its first predicted frame
  const Divergence d = find_divergence(r, contact_config(), o);
  EXPECT_FALSE(d.threshold_derived);
  EXPECT_EQ(d.threshold, 0.0015);
  EXPECT_EQ(d.frame, 2);
  EXPECT_EQ(d.object, 3);
  EXPECT_EQ(d.objects[1].object, 2);
  EXPECT_EQ(d.objects[1].frame, 7);
  // A jump that comes sooner is found sooner.
  EXPECT_EQ(find_divergence(make_rollout(5, 0.002), contact_config()).frame, 4);
}

TEST(Divergence, ARolloutWhoseErrorNeverGrowsHasNone) {
  Rollout r = make_rollout(8, 0.0);
  r.predicted = r.truth;
  const Divergence d = find_divergence(r, contact_config());
  EXPECT_FALSE(d.found());
  EXPECT_EQ(d.object, -1);
  EXPECT_TRUE(d.contacts.empty());
  EXPECT_EQ(d.objects.size(), 3u);
}

TEST(Divergence, ContactsAreTheModelsOwnRelationalPairs) {
  const Rollout touching = make_rollout(8, 0.0, 0.02);
  EXPECT_EQ(model_contacts(touching, 4, contact_config()).size(), 2u);
  const Rollout apart = make_rollout(8, 0.0, 0.5);
  EXPECT_TRUE(model_contacts(apart, 4, contact_config()).empty());
  EXPECT_THROW(model_contacts(touching, kFrames, contact_config()), ValueError);
}

}  // namespace
}  // namespace dynscope
