// Tests of PLY/PCD export: read back with PCL, compare positions and labels; bad input errors.
#include "engine/io/point_export.h"

#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_types.h>

#include <fstream>
#include <iterator>

#include "tests/io/io_test_util.h"

namespace dynscope {
namespace {

using test::error_of;
using test::expect_contains;

class PointExportTest : public ::testing::Test {
 protected:
  void SetUp() override {
    Rng rng(11);
    points_.resize(257, 3);
    for (Eigen::Index i = 0; i < points_.rows(); ++i) {
      points_.row(i) << rng.normal() * 3, rng.normal(), 10 + rng.uniform();
      ids_.push_back(static_cast<int32_t>(rng.uniform_int(0, 4) * 1000 + 7));
    }
  }

  void expect_cloud_matches(const pcl::PointCloud<pcl::PointXYZL>& cloud) {
    ASSERT_EQ(cloud.size(), static_cast<size_t>(points_.rows()));
    for (size_t i = 0; i < cloud.size(); ++i) {
      const auto r = static_cast<Eigen::Index>(i);
      EXPECT_EQ(cloud[i].x, static_cast<float>(points_(r, 0)));
      EXPECT_EQ(cloud[i].y, static_cast<float>(points_(r, 1)));
      EXPECT_EQ(cloud[i].z, static_cast<float>(points_(r, 2)));
      EXPECT_EQ(cloud[i].label, static_cast<uint32_t>(ids_[i]));
    }
  }

  test::TempDir dir_;
  Points points_;
  std::vector<int32_t> ids_;
};

TEST_F(PointExportTest, PlyRoundTripsThroughPcl) {
  const std::string path = dir_.file("points.ply");
  export_points_ply(path, points_, ids_);
  pcl::PointCloud<pcl::PointXYZL> cloud;
  ASSERT_EQ(pcl::io::loadPLYFile(path, cloud), 0);
  expect_cloud_matches(cloud);
  std::ifstream in(path, std::ios::binary);
  const std::string content((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string header = content.substr(0, content.find("end_header"));
  expect_contains(header, {"format binary_little_endian", "element vertex 257", "label"});
  EXPECT_EQ(header.find("camera"), std::string::npos) << header;
}

TEST_F(PointExportTest, PcdRoundTripsThroughPcl) {
  const std::string path = dir_.file("points.pcd");
  export_points_pcd(path, points_, ids_);
  pcl::PointCloud<pcl::PointXYZL> cloud;
  ASSERT_EQ(pcl::io::loadPCDFile(path, cloud), 0);
  expect_cloud_matches(cloud);
}

TEST_F(PointExportTest, SizeMismatchIsAValueError) {
  ids_.pop_back();
  expect_contains(
      error_of<ValueError>([&] { export_points_ply(dir_.file("a.ply"), points_, ids_); }),
      {"object_ids", "256 ids for 257 points"});
  expect_contains(
      error_of<ValueError>([&] { export_points_pcd(dir_.file("a.pcd"), points_, ids_); }),
      {"object_ids"});
  EXPECT_TRUE(dir_.entries().empty());
}

TEST_F(PointExportTest, NegativeIdsAndEmptyInputAreValueErrors) {
  ids_[5] = -1;
  expect_contains(
      error_of<ValueError>([&] { export_points_ply(dir_.file("a.ply"), points_, ids_); }),
      {"negative id -1 at index 5"});
  expect_contains(
      error_of<ValueError>([&] { export_points_pcd(dir_.file("a.pcd"), Points(0, 3), {}); }),
      {"points"});
}

TEST_F(PointExportTest, UnwritablePathIsAnIoErrorAndKeepsTheOldFile) {
  const std::string bad = dir_.file("no-such-dir/points.ply");
  expect_contains(error_of<IoError>([&] { export_points_ply(bad, points_, ids_); }), {bad});
  expect_contains(error_of<IoError>([&] { export_points_pcd(bad, points_, ids_); }), {bad});
  const std::string good = dir_.file("points.pcd");
  test::write_text(good, "previous content");
  ids_.pop_back();
  EXPECT_THROW(export_points_pcd(good, points_, ids_), ValueError);
  std::ifstream in(good);
  std::string content;
  std::getline(in, content);
  EXPECT_EQ(content, "previous content");
  EXPECT_EQ(dir_.entries(), std::vector<std::string>{"points.pcd"});
}

}  // namespace
}  // namespace dynscope
