// Baseline initializers: comparable to Free-Init at rest, wrong in motion (the paper's point).
#include <freeinit/baselines.h>
#include <freeinit/rotation.h>
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <random>
#include <vector>

#include "analytic_motion.h"

namespace freeinit {
namespace {

constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;

struct Data {
  std::vector<ImuSample> imu;
  std::vector<LidarFrame> frames;
  Extrinsics extrinsics = test::testExtrinsics();
  test::AnalyticMotion motion;
  Vec3 b_g = Vec3(0.01, -0.02, 0.015);
  Vec3 b_a = Vec3(0.08, -0.06, 0.1);
  double t0 = 1700000000.0;
};

/// IMU at 200 Hz for `duration` s and 10 Hz LiDAR frames of static points (plus 10% moving ones
/// with wrong Doppler) whose points are all measured at the frame stamp.
Data makeData(double motion_scale, double duration, unsigned seed = 7) {
  Data d;
  d.motion = test::AnalyticMotion(motion_scale);
  std::mt19937 rng(seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const Vec3 g_w(0, 0, -kGravity);
  const int n = static_cast<int>(std::round(duration * 200.0));
  for (int k = 0; k < n; ++k) {
    const double t = k / 200.0;
    const test::MotionState m = d.motion.at(t);
    ImuSample s;
    s.t = d.t0 + t;
    s.gyro = m.omega_b + d.b_g + 0.002 * Vec3(n01(rng), n01(rng), n01(rng));
    s.accel =
        m.R_wb.transpose() * (m.a_w - g_w) + d.b_a + 0.02 * Vec3(n01(rng), n01(rng), n01(rng));
    d.imu.push_back(s);
  }
  for (double t = 0.0; t < duration; t += 0.1) {
    const test::MotionState m = d.motion.at(t);
    const Vec3 v_b = m.R_wb.transpose() * m.v_w;
    const Vec3 v_l = d.extrinsics.R_bl.transpose() * (v_b + m.omega_b.cross(d.extrinsics.p_bl));
    LidarFrame f;
    f.stamp = d.t0 + t;
    for (int i = 0; i < 2000; ++i) {
      // Directions in a 120 x 30 deg field of view around the LiDAR x axis.
      const double az = (u01(rng) - 0.5) * 120.0 / kRadToDeg;
      const double el = (u01(rng) - 0.5) * 30.0 / kRadToDeg;
      const Vec3 dir(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
      const double range = 5.0 + 30.0 * u01(rng);
      DopplerPoint p;
      p.p_l = (range * dir).cast<float>();
      double doppler = -dir.dot(v_l) + 0.03 * n01(rng);
      if (i % 10 == 0) doppler += 3.0 + 2.0 * u01(rng);  // a moving object
      p.doppler = static_cast<float>(doppler);
      f.points.push_back(p);
    }
    d.frames.push_back(f);
  }
  return d;
}

/// Tilt bound at rest: the unobservable horizontal accelerometer bias, plus 0.1 deg.
double tiltBoundDeg(const Data& d) {
  const Vec3 up_b = d.motion.at(0).R_wb.transpose() * Vec3::UnitZ();
  const Vec3 b_h = d.b_a - up_b * up_b.dot(d.b_a);
  return std::atan(b_h.norm() / kGravity) * kRadToDeg + 0.1;
}

double tiltErrorDeg(const InitialState& s, const Data& d, double t) {
  const Vec3 g_b_true = d.motion.at(t).R_wb.transpose() * Vec3(0, 0, -kGravity);
  return angleBetween(s.g_b(), g_b_true) * kRadToDeg;
}

TEST(Baselines, FastLio2AtRest) {
  const Data d = makeData(0.0, 1.0);
  const InitResult r = baselines::fastLio2(d.imu, 100);
  ASSERT_TRUE(r.state.ok()) << r.state.message;
  EXPECT_DOUBLE_EQ(r.state.timestamp, d.imu[99].t);
  EXPECT_LT(tiltErrorDeg(r.state, d, 0.0), tiltBoundDeg(d));
  EXPECT_LT((r.state.b_g - d.b_g).norm(), 1e-3);  // 0.002 / sqrt(100) per axis
  EXPECT_NEAR(yawOf(r.state.q_wb.toRotationMatrix()), 0.0, 1e-12);
  EXPECT_EQ(r.state.g_w, Vec3(0, 0, -kGravity));
  EXPECT_EQ(r.state.v_w, Vec3::Zero());
  EXPECT_EQ(r.state.b_a, Vec3::Zero());
  // The covariance is symmetric positive definite and says v and b_a were not measured.
  const Eigen::SelfAdjointEigenSolver<Cov18> eig(r.state.cov);
  EXPECT_GT(eig.eigenvalues().minCoeff(), 0.0);
  EXPECT_GE(r.state.cov(kVel, kVel), 1.0);
}

TEST(Baselines, DlioAtRest) {
  const Data d = makeData(0.0, 3.5);
  const InitResult r = baselines::dlio(d.imu, 3.0);
  ASSERT_TRUE(r.state.ok()) << r.state.message;
  EXPECT_NEAR(r.state.timestamp, d.t0 + 3.0, 0.006);
  EXPECT_LT(tiltErrorDeg(r.state, d, 0.0), tiltBoundDeg(d));
  EXPECT_LT((r.state.b_g - d.b_g).norm(), 1e-3);
  // DLIO measures the bias along gravity only.
  const Vec3 up_b = d.motion.at(0).R_wb.transpose() * Vec3::UnitZ();
  EXPECT_NEAR(r.state.b_a.dot(up_b), d.b_a.dot(up_b), 5e-3);
  const Vec3 up_est = -r.state.g_b().normalized();  // along the mean specific force
  EXPECT_LT(r.state.b_a.cross(up_est).norm(), 1e-9);
}

TEST(Baselines, NotEnoughData) {
  const Data d = makeData(0.0, 1.0);
  EXPECT_EQ(baselines::fastLio2(d.imu, 500).state.status, InitStatus::NotEnoughData);
  EXPECT_EQ(baselines::dlio(d.imu, 3.0).state.status, InitStatus::NotEnoughData);
  EXPECT_EQ(baselines::dopplerLeastSquares(d.imu, {}, d.extrinsics, 100).state.status,
            InitStatus::NotEnoughData);
}

TEST(Baselines, DopplerLeastSquaresAtRestAndInMotion) {
  for (double scale : {0.0, 1.0}) {
    const Data d = makeData(scale, 1.0);
    const InitResult r = baselines::dopplerLeastSquares(d.imu, d.frames, d.extrinsics, 100);
    ASSERT_TRUE(r.state.ok()) << r.state.message;
    // The last frame in the 0.5 s window is at t = 0.4 s (all its points measured then).
    const test::MotionState m = d.motion.at(0.4);
    const Vec3 v_b_true = m.R_wb.transpose() * m.v_w;
    // Its body velocity uses the frame's mean gyro (one sample here, with b_g and noise) for the
    // lever arm: ~|b_g| * |p_bl| of error, plus the LS noise (0.03 / sqrt(1800) per axis).
    EXPECT_LT((r.state.v_b() - v_b_true).norm(), 0.02) << "scale " << scale;
  }
}

// In motion the static-mean baselines are wrong by construction: zero velocity, a gravity
// direction corrupted by the body acceleration and a "gyro bias" that is the mean rotation rate.
TEST(Baselines, FastLio2FailsInMotion) {
  const Data d = makeData(1.0, 1.0);
  const InitResult r = baselines::fastLio2(d.imu, 100);
  ASSERT_TRUE(r.state.ok());
  const test::MotionState m = d.motion.at(r.state.timestamp - d.t0);
  // ~0.9 m/s at the window end: 18x the 0.05 m/s the estimator must reach.
  EXPECT_GT(m.v_w.norm(), 0.5);
  EXPECT_GT((r.state.v_w - m.v_w).norm(), 0.5);
  EXPECT_GT((r.state.b_g - d.b_g).norm(), 1.0);
  EXPECT_GT(tiltErrorDeg(r.state, d, r.state.timestamp - d.t0), 5.0);
}

}  // namespace
}  // namespace freeinit
