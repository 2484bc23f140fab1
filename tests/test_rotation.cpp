// SO(3) helpers: closed-form cases, round trips, gravity alignment, autodiff through Exp.
#include <ceres/jet.h>
#include <freeinit/rotation.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace freeinit {
namespace {

constexpr double kPi = 3.14159265358979323846;

TEST(Rotation, SkewIsCrossProduct) {
  const Vec3 a(0.3, -1.2, 2.0), b(-0.7, 0.4, 1.1);
  EXPECT_LT((skew(a) * b - a.cross(b)).norm(), 1e-15);
  EXPECT_LT((skew(a) + skew(a).transpose()).norm(), 1e-15);
}

TEST(Rotation, ExpClosedForm) {
  // Constant omega = 3 rad/s about z for 2 s gives 6 rad (i.e. 6 - 2 pi).
  const Mat3 R = Exp(Vec3(0, 0, 3.0) * 2.0);
  EXPECT_LT((R - Eigen::AngleAxisd(6.0, Vec3::UnitZ()).toRotationMatrix()).norm(), 1e-14);
  EXPECT_LT((Exp(Vec3::Zero()) - Mat3::Identity()).norm(), 1e-15);
  const Vec3 tiny(1e-7, -2e-7, 3e-8);
  EXPECT_LT((Exp(tiny) - (Mat3::Identity() + skew(tiny))).norm(), 1e-13);
}

TEST(Rotation, ExpLogRoundTrip) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 200; ++i) {
    Vec3 axis(u(rng), u(rng), u(rng));
    axis.normalize();
    const double angle = (i == 0 ? 1e-9 : i == 1 ? kPi - 1e-9 : kPi * std::abs(u(rng)));
    const Vec3 phi = angle * axis;
    const Mat3 R = Exp(phi);
    EXPECT_LT((R.transpose() * R - Mat3::Identity()).norm(), 1e-14);
    EXPECT_NEAR(R.determinant(), 1.0, 1e-14);
    EXPECT_LT((Exp(Log(R)) - R).norm(), 1e-12);
    if (angle < kPi - 1e-6) {
      EXPECT_LT((Log(R) - phi).norm(), 1e-9);
    }
  }
}

TEST(Rotation, ExpWorksWithJets) {
  // d/dphi of Exp(phi) * v at phi0 by autodiff vs central differences.
  using J = ceres::Jet<double, 3>;
  const Vec3 phi0(0.4, -0.3, 0.8), v(1.0, 2.0, -0.5);
  Eigen::Matrix<J, 3, 1> phi;
  for (int i = 0; i < 3; ++i) phi(i) = J(phi0(i), i);
  const Eigen::Matrix<J, 3, 1> y = Exp<J>(phi) * v.cast<J>();
  for (int j = 0; j < 3; ++j) {
    const double h = 1e-6;
    const Vec3 dp = Vec3::Unit(j) * h;
    const Vec3 num = (Exp(Vec3(phi0 + dp)) * v - Exp(Vec3(phi0 - dp)) * v) / (2 * h);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(y(i).v(j), num(i), 1e-8);
  }
}

TEST(Rotation, AlignToGravity) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 100; ++i) {
    const Mat3 R_true = Exp(Vec3(u(rng), u(rng), 3.0 * u(rng)));
    const Vec3 g_b = R_true.transpose() * Vec3(0, 0, -kGravity);
    const Mat3 R = alignToGravity(g_b);
    EXPECT_LT((R * g_b.normalized() - Vec3(0, 0, -1)).norm(), 1e-12);
    EXPECT_NEAR(yawOf(R), 0.0, 1e-12);
    EXPECT_LT((R.transpose() * R - Mat3::Identity()).norm(), 1e-14);
    // Same roll and pitch as the truth: they differ by a rotation about the world z axis only.
    const Mat3 D = R * R_true.transpose();
    EXPECT_LT((D * Vec3::UnitZ() - Vec3::UnitZ()).norm(), 1e-12);
  }
  // Level at rest: accelerometer reads +g up, so g_b = (0, 0, -g) gives the identity.
  EXPECT_LT((alignToGravity(Vec3(0, 0, -kGravity)) - Mat3::Identity()).norm(), 1e-15);
  // Pitch 90 deg: gravity along body -x... still maps to -z.
  EXPECT_LT((alignToGravity(Vec3(1, 0, 0)) * Vec3(1, 0, 0) - Vec3(0, 0, -1)).norm(), 1e-12);
}

TEST(Rotation, AngleBetween) {
  EXPECT_NEAR(angleBetween(Vec3(1, 0, 0), Vec3(0, 2, 0)), kPi / 2, 1e-15);
  EXPECT_NEAR(angleBetween(Vec3(1, 0, 0), Vec3(-3, 0, 0)), kPi, 1e-15);
  EXPECT_NEAR(angleBetween(Vec3(1, 0, 0), Vec3(1, 1e-9, 0)), 1e-9, 1e-20);
}

}  // namespace
}  // namespace freeinit
