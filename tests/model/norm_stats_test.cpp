// NormStatsAccumulator and PointState: statistics against direct computation, size checks.
#include "engine/model/norm_stats.h"

#include <gtest/gtest.h>

#include "engine/core/error.h"
#include "engine/core/rng.h"
#include "engine/model/point_state.h"

namespace dynscope {
namespace {

Points random_points(Eigen::Index n, Rng& rng) {
  Points p(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) p.row(i) << rng.normal(), rng.normal(), rng.normal();
  return p;
}

TEST(NormStatsTest, MatchesDirectMeanAndStd) {
  Rng rng(3);
  const Points a = random_points(50, rng), b = random_points(50, rng), c = random_points(50, rng);
  NormStatsAccumulator acc(TargetMode::kAcceleration);
  acc.add(a, b, c);
  const NormStats s = acc.finish();
  const Points v = b - a;
  const Points target = (c - b) - v;
  for (int k = 0; k < 3; ++k) {
    const double mean = v.col(k).mean();
    const double var = (v.col(k).array() - mean).square().mean();
    EXPECT_NEAR(s.velocity_mean[k], mean, 1e-12);
    EXPECT_NEAR(s.velocity_std[k], std::sqrt(var), 1e-9);
    const double tm = target.col(k).mean();
    EXPECT_NEAR(s.target_mean[k], tm, 1e-12);
    EXPECT_NEAR(s.target_std[k], std::sqrt((target.col(k).array() - tm).square().mean()), 1e-9);
  }
  EXPECT_NEAR(s.z_mean, b.col(2).mean(), 1e-12);
  EXPECT_EQ(acc.count(), 50);
}

TEST(NormStatsTest, VelocityTargetAndStdFloor) {
  Points p = Points::Zero(4, 3);
  NormStatsAccumulator acc(TargetMode::kVelocity);
  Points q = p;
  q.col(0).array() += 0.5;
  acc.add(p, p, q);
  const NormStats s = acc.finish(1e-3);
  EXPECT_DOUBLE_EQ(s.target_mean[0], 0.5);
  EXPECT_DOUBLE_EQ(s.target_std[0], 1e-3);
  EXPECT_DOUBLE_EQ(s.velocity_std[1], 1e-3);
}

TEST(NormStatsTest, RejectsEmptyAndMismatchedInput) {
  NormStatsAccumulator acc(TargetMode::kVelocity);
  EXPECT_THROW(acc.finish(), ValueError);
  EXPECT_THROW(acc.add(Points::Zero(3, 3), Points::Zero(4, 3), Points::Zero(3, 3)), ValueError);
}

TEST(PointStateTest, FromPositionsComputesVelocities) {
  Rng rng(1);
  const Points a = random_points(5, rng), b = random_points(5, rng), c = random_points(5, rng);
  const PointState s = PointState::from_positions(c, b, a, {1, 1, 2, 2, 2});
  EXPECT_TRUE(s.velocity.isApprox(c - b));
  EXPECT_TRUE(s.prev_velocity.isApprox(b - a));
  EXPECT_THROW(PointState::from_positions(c, b, a, {1, 2}), ValueError);
  Points bad = c;
  bad(0, 0) = std::nan("");
  EXPECT_THROW(PointState::from_positions(bad, b, a, {1, 1, 2, 2, 2}), ValueError);
}

}  // namespace
}  // namespace dynscope
