// Tests of the orbit camera: presets (z up), projection, fit, orbit/pan/zoom.
#include "render/camera.h"

#include <gtest/gtest.h>

#include "engine/core/error.h"

namespace dynscope::render {
namespace {

constexpr double kTol = 1e-9;

TEST(Camera, PresetsLookAlongTheDocumentedAxesWithZUp) {
  Camera c;
  c.set_preset(ViewPreset::kFront);
  EXPECT_TRUE(c.forward().isApprox(Vec3(0, 1, 0), kTol));
  EXPECT_TRUE(c.up().isApprox(Vec3(0, 0, 1), kTol));
  EXPECT_TRUE(c.right().isApprox(Vec3(1, 0, 0), kTol));
  c.set_preset(ViewPreset::kSide);
  EXPECT_TRUE(c.forward().isApprox(Vec3(-1, 0, 0), kTol));
  EXPECT_TRUE(c.up().isApprox(Vec3(0, 0, 1), kTol));
  c.set_preset(ViewPreset::kTop);
  EXPECT_TRUE(c.forward().isApprox(Vec3(0, 0, -1), kTol));
  EXPECT_TRUE(c.right().isApprox(Vec3(1, 0, 0), kTol));
  EXPECT_TRUE(c.up().isApprox(Vec3(0, 1, 0), kTol));
  c.set_preset(ViewPreset::kIso);
  EXPECT_GT(c.eye().z(), 0.0);
  EXPECT_GT(c.up().z(), 0.0);
  EXPECT_EQ(parse_preset("top"), ViewPreset::kTop);
  EXPECT_THROW(parse_preset("bottom"), ValueError);
}

TEST(Camera, ProjectsTargetToCentreAndUpwardsToSmallerRows) {
  Camera c;
  c.target = Vec3(1, 2, 3);
  c.distance = 4;
  const Vec3 centre = c.project(c.target, 320, 240);
  EXPECT_NEAR(centre.x(), 160.0, 1e-4);  // float matrices
  EXPECT_NEAR(centre.y(), 120.0, 1e-4);
  EXPECT_NEAR(centre.z(), 4.0, 1e-4);
  const Vec3 above = c.project(c.target + Vec3(0, 0, 0.5), 320, 240);
  EXPECT_LT(above.y(), centre.y());
  const Vec3 eye_view = (c.view_matrix().cast<double>() * c.eye().homogeneous()).head<3>();
  EXPECT_LT(eye_view.norm(), 1e-5);
}

TEST(Camera, FitKeepsEveryCornerInsideTheImage) {
  Aabb box;
  box.extend(Vec3(-3, -1, 0));
  box.extend(Vec3(5, 2, 1.5));
  for (ViewPreset p : {ViewPreset::kFront, ViewPreset::kSide, ViewPreset::kTop, ViewPreset::kIso}) {
    Camera c;
    c.set_preset(p);
    c.fit(box, 320.0 / 240.0);
    for (int i = 0; i < 8; ++i) {
      const Vec3 corner((i & 1) ? box.max.x() : box.min.x(), (i & 2) ? box.max.y() : box.min.y(),
                        (i & 4) ? box.max.z() : box.min.z());
      const Vec3 px = c.project(corner, 320, 240);
      EXPECT_GT(px.z(), 0.0);
      EXPECT_GE(px.x(), 0.0) << preset_name(p);
      EXPECT_LE(px.x(), 320.0) << preset_name(p);
      EXPECT_GE(px.y(), 0.0) << preset_name(p);
      EXPECT_LE(px.y(), 240.0) << preset_name(p);
    }
  }
}

TEST(Camera, OrbitPanZoom) {
  Camera c;
  const Vec3 target = c.target;
  c.orbit(30, 100);
  EXPECT_DOUBLE_EQ(c.pitch_deg, 90.0);
  EXPECT_NEAR((c.eye() - c.target).norm(), c.distance, 1e-9);
  c.pan(0.5, 0.0);
  EXPECT_NEAR((c.target - target).norm(), 0.5 * 2 * c.distance * std::tan(c.fov_deg * M_PI / 360),
              1e-9);
  c.zoom(0.5);
  EXPECT_DOUBLE_EQ(c.distance, 5.0);
  EXPECT_THROW(c.zoom(0.0), ValueError);
  c.distance = -1;
  EXPECT_THROW(c.validate(), ValueError);
}

}  // namespace
}  // namespace dynscope::render
