// Tests of Pose and Aabb.
#include "engine/core/types.h"

#include <gtest/gtest.h>

namespace dynscope {
namespace {

TEST(PoseTest, ApplyMatchesPointwiseTransform) {
  Pose pose;
  pose.position = Vec3(1, -2, 3);
  pose.rotation = Quat(Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()));
  Points local(3, 3);
  local << 0, 0, 0, 1, 0, 0, 0.5, -1, 2;
  const Points world = pose.apply(local);
  for (int i = 0; i < 3; ++i) {
    const Vec3 expected = pose.rotation * Vec3(local.row(i).transpose()) + pose.position;
    EXPECT_TRUE(world.row(i).transpose().isApprox(expected, 1e-12));
    EXPECT_TRUE(pose.apply(Vec3(local.row(i).transpose())).isApprox(expected, 1e-12));
  }
}

TEST(AabbTest, OfPointsAndEmpty) {
  EXPECT_TRUE(Aabb::of(Points(0, 3)).empty());
  Points p(2, 3);
  p << -1, 2, 3, 4, -5, 6;
  const Aabb box = Aabb::of(p);
  EXPECT_FALSE(box.empty());
  EXPECT_EQ(box.min, Vec3(-1, -5, 3));
  EXPECT_EQ(box.max, Vec3(4, 2, 6));
  Aabb merged;
  merged.extend(Aabb());
  EXPECT_TRUE(merged.empty());
  merged.extend(box);
  EXPECT_EQ(merged.max, box.max);
}

}  // namespace
}  // namespace dynscope
