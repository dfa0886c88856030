// Metrics on hand-made point sets: point error, minimum distance, contact rule.
#include "engine/rollout/metrics.h"

#include <gtest/gtest.h>

#include "engine/core/error.h"

namespace dynscope {
namespace {

TEST(MetricsTest, MeanPointErrorAveragesDistances) {
  Points a(2, 3), b(2, 3);
  a << 0, 0, 0, 1, 1, 1;
  b << 3, 4, 0, 1, 1, 2;
  EXPECT_DOUBLE_EQ(mean_point_error(a, b), (5.0 + 1.0) / 2);
  EXPECT_THROW(mean_point_error(a, Points(1, 3)), ValueError);
}

TEST(MetricsTest, MinDistanceIsTheClosestPair) {
  Points a(2, 3), b(3, 3);
  a << 0, 0, 0, 10, 0, 0;
  b << 13, 0, 0, 10, 0, 2.5, -5, 0, 0;
  EXPECT_DOUBLE_EQ(min_distance(a, b), 2.5);
  EXPECT_THROW(min_distance(a, Points(0, 3)), ValueError);
}

TEST(MetricsTest, ContactWhenAnyFrameIsBelowThreshold) {
  EXPECT_TRUE(contact_predicted({0.5, 0.3, 0.04, 0.2}, 0.05));
  EXPECT_FALSE(contact_predicted({0.5, 0.3, 0.05, 0.2}, 0.05));  // strict
  EXPECT_FALSE(contact_predicted({}, 0.05));
}

TEST(MetricsTest, SelectRowsKeepsOrder) {
  Points p(4, 3);
  p << 0, 0, 0, 1, 1, 1, 2, 2, 2, 3, 3, 3;
  const Points s = select_rows(p, {7, 8, 7, 9}, 7);
  ASSERT_EQ(s.rows(), 2);
  EXPECT_EQ(s(1, 0), 2);
}

}  // namespace
}  // namespace dynscope
