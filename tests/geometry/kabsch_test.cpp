// Tests for the Kabsch rigid fit: recovery, optimality, degenerate sets and reflections.
#include "engine/geometry/kabsch.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <string>

#include "engine/core/error.h"
#include "engine/core/rng.h"

namespace dynscope {
namespace {

Quat random_rotation(Rng& rng) {
  Quat q(rng.normal(), rng.normal(), rng.normal(), rng.normal());
  return q.normalized();
}

Points random_points(Rng& rng, Eigen::Index n, double scale = 1.0) {
  Points p(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) p.row(i) << rng.normal(), rng.normal(), rng.normal();
  return p * scale;
}

double residual(const Pose& pose, const Points& source, const Points& target) {
  return (pose.apply(source) - target).squaredNorm();
}

void expect_proper_rotation(const Pose& pose) {
  EXPECT_NEAR(pose.rotation.norm(), 1.0, 1e-12);
  const Mat3 r = pose.rotation.toRotationMatrix();
  EXPECT_NEAR(r.determinant(), 1.0, 1e-12);
  EXPECT_TRUE((r.transpose() * r).isApprox(Mat3::Identity(), 1e-12));
}

TEST(KabschTest, RecoversRandomRigidTransforms) {
  for (uint64_t seed = 0; seed < 50; ++seed) {
    Rng rng(seed);
    Pose truth;
    truth.rotation = random_rotation(rng);
    truth.position = Vec3(rng.uniform(-5, 5), rng.uniform(-5, 5), rng.uniform(-5, 5));
    const Points source = random_points(rng, 3 + static_cast<Eigen::Index>(seed % 20));
    const Pose fit = fit_rigid_transform(source, truth.apply(source));
    expect_proper_rotation(fit);
    EXPECT_LT(fit.rotation.angularDistance(truth.rotation), 1e-9) << "seed " << seed;
    EXPECT_LT((fit.position - truth.position).norm(), 1e-9) << "seed " << seed;
  }
}

TEST(KabschTest, NoisyTargetsFitAtLeastAsWellAsTheTruth) {
  // The fit minimises the squared residual, so it cannot be worse than the generating transform.
  for (uint64_t seed = 100; seed < 120; ++seed) {
    Rng rng(seed);
    Pose truth;
    truth.rotation = random_rotation(rng);
    truth.position = Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    const Points source = random_points(rng, 40);
    const Points target = truth.apply(source) + random_points(rng, 40, 0.05);
    const Pose fit = fit_rigid_transform(source, target);
    expect_proper_rotation(fit);
    const double best = residual(fit, source, target);
    EXPECT_LE(best, residual(truth, source, target) + 1e-12);
    // Small perturbations of the fitted pose only make it worse (a local check of optimality).
    for (int t = 0; t < 10; ++t) {
      Pose nudged = fit;
      nudged.rotation =
          (Quat(Eigen::AngleAxisd(1e-3, random_points(rng, 1).row(0).normalized())) * fit.rotation)
              .normalized();
      nudged.position += 1e-3 * random_points(rng, 1).row(0).transpose();
      EXPECT_GT(residual(nudged, source, target), best);
    }
  }
}

TEST(KabschTest, OnePointGivesAnExactTranslationAndAProperRotation) {
  Points source(1, 3), target(1, 3);
  source << 1, 2, 3;
  target << -4, 0.5, 7;
  const Pose fit = fit_rigid_transform(source, target);
  expect_proper_rotation(fit);
  EXPECT_LT((fit.apply(Vec3(1, 2, 3)) - Vec3(-4, 0.5, 7)).norm(), 1e-12);
}

TEST(KabschTest, TwoPointsAndCollinearSetsFitExactly) {
  for (uint64_t seed = 0; seed < 10; ++seed) {
    Rng rng(seed);
    Pose truth;
    truth.rotation = random_rotation(rng);
    truth.position = Vec3(rng.normal(), rng.normal(), rng.normal());
    const Vec3 a(rng.normal(), rng.normal(), rng.normal());
    const Vec3 dir = Vec3(rng.normal(), rng.normal(), rng.normal()).normalized();
    for (const Eigen::Index n : {2, 7}) {
      Points source(n, 3);
      for (Eigen::Index i = 0; i < n; ++i) {
        source.row(i) = (a + dir * (rng.uniform(-2, 2) + static_cast<double>(i))).transpose();
      }
      const Points target = truth.apply(source);
      const Pose fit = fit_rigid_transform(source, target);
      expect_proper_rotation(fit);
      // The rotation about the line is undetermined, but the points themselves must match.
      EXPECT_LT(std::sqrt(residual(fit, source, target)), 1e-9) << "seed " << seed << " n " << n;
    }
  }
}

TEST(KabschTest, PlanarAndNearlyDegenerateSetsRecoverTheTransform) {
  for (uint64_t seed = 0; seed < 20; ++seed) {
    Rng rng(seed);
    Pose truth;
    truth.rotation = random_rotation(rng);
    truth.position = Vec3(rng.normal(), rng.normal(), rng.normal());
    // Exactly planar, nearly planar (1e-7 thick) and nearly collinear (1e-4 wide) sets: each
    // still determines the rotation uniquely.
    for (const Vec3& spread : {Vec3(1, 1, 0), Vec3(1, 1, 1e-7), Vec3(1, 1e-4, 1e-4)}) {
      Points source = random_points(rng, 12);
      for (int c = 0; c < 3; ++c) source.col(c) *= spread[c];
      const Pose fit = fit_rigid_transform(source, truth.apply(source));
      expect_proper_rotation(fit);
      EXPECT_LT(std::sqrt(residual(fit, source, truth.apply(source))), 1e-9);
      // A thin direction of width w pins the rotation only to about machine error / w.
      EXPECT_LT(fit.rotation.angularDistance(truth.rotation), 1e-6)
          << "seed " << seed << " spread " << spread.transpose();
    }
  }
}

TEST(KabschTest, ReflectedTargetsStillGiveAProperRotation) {
  for (uint64_t seed = 0; seed < 20; ++seed) {
    Rng rng(seed);
    const Points source = random_points(rng, 15);
    Points mirrored = source;
    mirrored.col(0) *= -1.0;
    const Pose fit = fit_rigid_transform(source, mirrored);
    expect_proper_rotation(fit);
    // The best proper rotation beats the identity and a few random rotations.
    const double best = residual(fit, source, mirrored);
    EXPECT_LE(best, residual(Pose(), source, mirrored) + 1e-12);
    for (int t = 0; t < 5; ++t) {
      Pose other;
      other.rotation = random_rotation(rng);
      other.position = fit.position;
      EXPECT_LE(best, residual(other, source, mirrored) + 1e-12);
    }
  }
  // A planar set mirrored across its own plane is unchanged: the fit must be exact.
  Rng rng(5);
  Points planar = random_points(rng, 10);
  planar.col(2).setZero();
  Pose truth;
  truth.rotation = random_rotation(rng);
  Points target = planar;
  target.col(2) *= -1.0;
  target = truth.apply(target);
  const Pose fit = fit_rigid_transform(planar, target);
  expect_proper_rotation(fit);
  EXPECT_LT(std::sqrt(residual(fit, planar, target)), 1e-9);
}

TEST(KabschTest, EqualsEigensUmeyamaIncludingFarFromTheOrigin) {
  // The reference formulation: Eigen::umeyama without scaling, on the same points.
  for (uint64_t seed = 200; seed < 230; ++seed) {
    Rng rng(seed);
    const double offset = seed % 3 == 0 ? 0.0 : (seed % 3 == 1 ? 1.0e4 : -3.0e6);
    Pose truth;
    truth.rotation = random_rotation(rng);
    truth.position = Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    Points source = random_points(rng, 2 + static_cast<Eigen::Index>(seed % 700));
    source.array() += offset;
    const Points target =
        truth.apply(source) + random_points(rng, source.rows(), seed % 2 == 0 ? 0.0 : 0.01);
    const Eigen::Matrix4d reference = Eigen::umeyama(source.transpose(), target.transpose(), false);
    const Pose fit = fit_rigid_transform(source, target);
    expect_proper_rotation(fit);
    const Mat3 r = fit.rotation.toRotationMatrix();
    const double scale = 1.0 + std::abs(offset);
    EXPECT_LT((r - reference.block<3, 3>(0, 0)).cwiseAbs().maxCoeff(), 1e-9) << "seed " << seed;
    EXPECT_LT((fit.position - reference.block<3, 1>(0, 3)).cwiseAbs().maxCoeff(), 1e-9 * scale)
        << "seed " << seed;
  }
}

TEST(KabschTest, BadInputsThrowNamedValueErrors) {
  Points a(3, 3), b(2, 3);
  a.setRandom();
  b.setRandom();
  auto name_of = [](const auto& f) {
    try {
      f();
    } catch (const ValueError& e) {
      return e.name();
    }
    return std::string("no error");
  };
  EXPECT_EQ(name_of([&] { fit_rigid_transform(a, b); }), "target");
  EXPECT_EQ(name_of([&] { fit_rigid_transform(Points(0, 3), Points(0, 3)); }), "source");
  Points nan = a;
  nan(1, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(name_of([&] { fit_rigid_transform(nan, a); }), "source");
  EXPECT_EQ(name_of([&] { fit_rigid_transform(a, nan); }), "target");
  Points inf = a;
  inf(2, 0) = std::numeric_limits<double>::infinity();
  inf(0, 0) = -std::numeric_limits<double>::infinity();
  EXPECT_EQ(name_of([&] { fit_rigid_transform(inf, a); }), "source");
  EXPECT_EQ(name_of([&] { fit_rigid_transform(a, inf); }), "target");
  // Finite coordinates whose sums overflow: a clear error, not a pose of infinities.
  Points huge(3, 3);
  huge << 1.7e308, -1.7e308, 1.7e308, 1.7e308, 1.7e308, -1.7e308, 1.7e308, 1.0, 1.0;
  EXPECT_EQ(name_of([&] { fit_rigid_transform(huge, huge); }), "source");
}

}  // namespace
}  // namespace dynscope
