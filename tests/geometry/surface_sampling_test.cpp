// Tests for area-weighted surface sampling: faces by area, uniform inside, on the surface.
#include "engine/geometry/surface_sampling.h"

#include <gtest/gtest.h>

#include <cmath>

#include "engine/core/error.h"

namespace dynscope {
namespace {

// Two right triangles of area 0.5 and 4.5 (ratio 1:9), far apart, plus a zero-area face.
Mesh two_triangles() {
  Mesh m;
  m.vertices.resize(8, 3);
  m.vertices << 0, 0, 0, 1, 0, 0, 0, 1, 0,  // small, z = 0
      10, 0, 1, 13, 0, 1, 10, 3, 1,         // large, z = 1
      5, 5, 5, 6, 6, 6;
  m.faces.resize(3, 3);
  m.faces << 0, 1, 2, 6, 7, 6, 3, 4, 5;  // the middle face is degenerate
  return m;
}

// Barycentric coordinates of p in triangle (a, b, c) and its distance to the triangle's plane.
Vec3 barycentric(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, double* off_plane) {
  const Vec3 n = (b - a).cross(c - a);
  *off_plane = std::abs((p - a).dot(n.normalized()));
  const double area = n.norm();
  const double wa = (b - p).cross(c - p).dot(n) / (area * area);
  const double wb = (c - p).cross(a - p).dot(n) / (area * area);
  return Vec3(wa, wb, 1.0 - wa - wb);
}

TEST(SurfaceSamplingTest, FacesAreChosenInProportionToArea) {
  Rng rng(42);
  const int64_t n = 20000;
  const SurfaceSamples s = sample_surface(two_triangles(), n, rng);
  ASSERT_EQ(s.points.rows(), n);
  ASSERT_EQ(s.face.size(), static_cast<size_t>(n));
  int64_t small = 0, large = 0;
  for (const int32_t f : s.face) {
    ASSERT_NE(f, 1) << "the zero-area face was sampled";
    small += f == 0 ? 1 : 0;
    large += f == 2 ? 1 : 0;
  }
  EXPECT_EQ(small + large, n);
  // Chi-square with one degree of freedom; 10.83 is the 0.1 % critical value.
  const double e_small = 0.1 * n, e_large = 0.9 * n;
  const double chi2 = (small - e_small) * (small - e_small) / e_small +
                      (large - e_large) * (large - e_large) / e_large;
  EXPECT_LT(chi2, 10.83) << "small " << small << " large " << large;
}

TEST(SurfaceSamplingTest, PointsLieOnTheirFaceAndFillItUniformly) {
  const Mesh m = two_triangles();
  Rng rng(3);
  const SurfaceSamples s = sample_surface(m, 8000, rng);
  // Midpoint subdivision splits each triangle into four equal-area parts: expect 1/4 in each.
  int counts[4] = {0, 0, 0, 0};
  int on_large = 0;
  for (Eigen::Index i = 0; i < s.points.rows(); ++i) {
    const int32_t f = s.face[static_cast<size_t>(i)];
    const Vec3 a = m.vertices.row(m.faces(f, 0)).transpose();
    const Vec3 b = m.vertices.row(m.faces(f, 1)).transpose();
    const Vec3 c = m.vertices.row(m.faces(f, 2)).transpose();
    double off_plane = 0.0;
    const Vec3 w = barycentric(s.points.row(i).transpose(), a, b, c, &off_plane);
    EXPECT_LT(off_plane, 1e-12);
    EXPECT_GE(w.minCoeff(), -1e-12);
    EXPECT_LE(w.maxCoeff(), 1.0 + 1e-12);
    if (f != 2) continue;
    ++on_large;
    const int part = w[0] > 0.5 ? 0 : w[1] > 0.5 ? 1 : w[2] > 0.5 ? 2 : 3;
    ++counts[part];
  }
  double chi2 = 0.0;
  for (const int c : counts) chi2 += (c - on_large / 4.0) * (c - on_large / 4.0) / (on_large / 4.0);
  // Three degrees of freedom; 16.27 is the 0.1 % critical value.
  EXPECT_LT(chi2, 16.27) << counts[0] << " " << counts[1] << " " << counts[2] << " " << counts[3];
}

TEST(SurfaceSamplingTest, SameSeedSameSamplesOtherSeedOtherSamples) {
  const Mesh sphere = make_sphere_mesh(1.0);
  Rng a(9), b(9), c(10);
  const SurfaceSamples sa = sample_surface(sphere, 500, a);
  const SurfaceSamples sb = sample_surface(sphere, 500, b);
  const SurfaceSamples sc = sample_surface(sphere, 500, c);
  EXPECT_EQ(sa.points, sb.points);
  EXPECT_EQ(sa.face, sb.face);
  EXPECT_NE(sa.points, sc.points);
  EXPECT_EQ(sample_surface(sphere, 0, a).points.rows(), 0);
}

TEST(SurfaceSamplingTest, BadInputsThrowNamedValueErrors) {
  Rng rng(1);
  auto name_of = [&](const Mesh& m, int64_t count) {
    try {
      sample_surface(m, count, rng);
    } catch (const ValueError& e) {
      return e.name();
    }
    return std::string("no error");
  };
  EXPECT_EQ(name_of(make_box_mesh(Vec3::Ones()), -1), "count");
  EXPECT_EQ(name_of(Mesh(), 10), "mesh");
  Mesh flat = make_box_mesh(Vec3::Ones());
  flat.vertices.setZero();
  EXPECT_EQ(name_of(flat, 10), "mesh");
  Mesh broken = make_box_mesh(Vec3::Ones());
  broken.faces(0, 0) = -2;
  EXPECT_EQ(name_of(broken, 10), "mesh");
}

}  // namespace
}  // namespace dynscope
