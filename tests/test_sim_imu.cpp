// Integrating the simulated IMU (true biases removed, noise off) from the true initial state must
// reproduce the ground-truth pose to within the integration error of the scheme.
#include <freeinit/sim/presets.h>

#include <gtest/gtest.h>

#include <cmath>

namespace freeinit::sim {
namespace {

Mat3 skew(const Vec3& w) {
  Mat3 S;
  S << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return S;
}

Mat3 orthonormalize(const Mat3& R) { return Quat(R).normalized().toRotationMatrix(); }

/// Bias-free IMU signal at the midpoint of samples k, k+1: cubic (4-point) interpolation, whose
/// error is O(h^4) instead of the O(h^2) of a linear one; linear at the ends.
template <typename Get>
Vec3 midpoint(const std::vector<ImuSample>& imu, std::size_t k, Get get) {
  if (k == 0 || k + 2 >= imu.size()) return 0.5 * (get(imu[k]) + get(imu[k + 1]));
  return (-get(imu[k - 1]) + 9.0 * get(imu[k]) + 9.0 * get(imu[k + 1]) - get(imu[k + 2])) / 16.0;
}

struct IntegrationError {
  double attitude = 0;  ///< [rad] max over samples
  double position = 0;  ///< [m]
  double velocity = 0;  ///< [m/s]
};

/// Classical RK4 on (R_wb, v_w, p_w) with Rdot = R [omega]x, vdot = R f + g, pdot = v, the
/// stage values at t + h/2 from the interpolated samples.
IntegrationError integrate(const Recording& rec, double horizon) {
  const Vec3 g_w = rec.g_w;
  auto gyro = [&](const ImuSample& s) -> Vec3 { return s.gyro - rec.b_g; };
  auto acc = [&](const ImuSample& s) -> Vec3 { return s.accel - rec.b_a; };
  const TruthState s0 = rec.truth(rec.imu.front().t);
  Mat3 R = s0.R_wb;
  Vec3 v = s0.v_w, p = s0.p_w;
  IntegrationError err;
  for (std::size_t k = 0; k + 1 < rec.imu.size(); ++k) {
    const double h = rec.imu[k + 1].t - rec.imu[k].t;
    if (rec.imu[k + 1].t - rec.imu.front().t > horizon + 1e-9) break;
    const Vec3 w0 = gyro(rec.imu[k]), w1 = gyro(rec.imu[k + 1]), wm = midpoint(rec.imu, k, gyro);
    const Vec3 f0 = acc(rec.imu[k]), f1 = acc(rec.imu[k + 1]), fm = midpoint(rec.imu, k, acc);
    const Mat3 kR1 = R * skew(w0);
    const Vec3 kv1 = R * f0 + g_w, kp1 = v;
    const Mat3 R2 = R + 0.5 * h * kR1;
    const Mat3 kR2 = R2 * skew(wm);
    const Vec3 kv2 = R2 * fm + g_w, kp2 = v + 0.5 * h * kv1;
    const Mat3 R3 = R + 0.5 * h * kR2;
    const Mat3 kR3 = R3 * skew(wm);
    const Vec3 kv3 = R3 * fm + g_w, kp3 = v + 0.5 * h * kv2;
    const Mat3 R4 = R + h * kR3;
    const Mat3 kR4 = R4 * skew(w1);
    const Vec3 kv4 = R4 * f1 + g_w, kp4 = v + h * kv3;
    R = orthonormalize(R + h / 6.0 * (kR1 + 2.0 * kR2 + 2.0 * kR3 + kR4));
    p += h / 6.0 * (kp1 + 2.0 * kp2 + 2.0 * kp3 + kp4);
    v += h / 6.0 * (kv1 + 2.0 * kv2 + 2.0 * kv3 + kv4);
    const TruthState s = rec.truth(rec.imu[k + 1].t);
    err.attitude = std::max(err.attitude, Eigen::AngleAxisd(s.R_wb.transpose() * R).angle());
    err.position = std::max(err.position, (s.p_w - p).norm());
    err.velocity = std::max(err.velocity, (s.v_w - v).norm());
  }
  return err;
}

Recording noiseFreeImu(const std::string& name) {
  ScenarioConfig c = preset(name, 3);
  c.duration = 1.0;
  c.points_per_frame = 0;  // IMU only
  c.gyro_sigma = 0;
  c.accel_sigma = 0;
  return simulate(c);
}

// Bounds: RK4 is O(h^4), so at 200 Hz the error is dominated by reconstructing the signals between
// samples: the 4-point midpoint has error (3/128) h^4 f'''' and the first step's linear midpoint
// h^2/8 f''. For dyna_04 (10 rad/s at 2-2.5 Hz, hand shake up to 3.3 Hz) and dyna_05 (suspension
// up to 4 Hz) these give 1e-5..1e-4 m/s of velocity error over 1 s. Measured with seed 3:
// dyna_04 1.6e-5 rad, 5.5e-5 m, 1.5e-4 m/s; dyna_05 1.0e-6 rad, 1.9e-5 m, 3.6e-5 m/s. Bounds are
// ~3x the rotational measurement, and ~100x below what the noise of a real IMU produces over 1 s
// (gyro white noise alone: ~1e-4 rad, accel: ~1e-3 m/s).
TEST(SimImu, IntegrationReproducesTruthRotational) {
  const Recording rec = noiseFreeImu("dyna_04");
  ASSERT_EQ(rec.imu.size(), 201u);
  const IntegrationError e = integrate(rec, 1.0);
  std::printf("dyna_04: attitude %.3g rad, position %.3g m, velocity %.3g m/s\n", e.attitude,
              e.position, e.velocity);
  EXPECT_LT(e.attitude, 5e-5);
  EXPECT_LT(e.position, 2e-4);
  EXPECT_LT(e.velocity, 5e-4);
}

TEST(SimImu, IntegrationReproducesTruthVehicular) {
  const Recording rec = noiseFreeImu("dyna_05");
  const IntegrationError e = integrate(rec, 1.0);
  std::printf("dyna_05: attitude %.3g rad, position %.3g m, velocity %.3g m/s\n", e.attitude,
              e.position, e.velocity);
  EXPECT_LT(e.attitude, 5e-5);
  EXPECT_LT(e.position, 2e-4);
  EXPECT_LT(e.velocity, 5e-4);
}

TEST(SimImu, NoiseFreeSamplesAreExactTruth) {
  const Recording rec = noiseFreeImu("stat_02");
  for (const ImuSample& m : rec.imu) {
    const TruthState s = rec.truth(m.t);
    EXPECT_LT((m.gyro - rec.b_g - s.omega_b).norm(), 1e-12);
    EXPECT_LT((m.accel - rec.b_a - s.R_wb.transpose() * (s.a_w - rec.g_w)).norm(), 1e-12);
  }
  // At rest the accelerometer measures -g rotated into the body, i.e. +9.81 m/s^2 "up".
  EXPECT_NEAR((rec.imu.front().accel - rec.b_a).norm(), kGravity, 1e-12);
}

TEST(SimImu, BiasesAndNoiseAreInRange) {
  ScenarioConfig c = preset("stat_01", 11);
  c.duration = 1.0;
  c.points_per_frame = 0;
  const Recording rec = simulate(c);
  for (int k = 0; k < 3; ++k) {
    EXPECT_GE(std::abs(rec.b_g[k]), 0.005);
    EXPECT_LE(std::abs(rec.b_g[k]), 0.02);
    EXPECT_GE(std::abs(rec.b_a[k]), 0.02);
    EXPECT_LE(std::abs(rec.b_a[k]), 0.15);
  }
  // Standing still for 1.5 s: the gyro residual is pure white noise. With 201 samples x 3 axes the
  // sample std has a relative standard error 1/sqrt(2*603) = 2.9 %: allow 15 %.
  double sum2 = 0;
  int n = 0;
  for (const ImuSample& m : rec.imu) {
    sum2 += (m.gyro - rec.b_g).squaredNorm();
    n += 3;
  }
  EXPECT_NEAR(std::sqrt(sum2 / n), c.gyro_sigma, 0.15 * c.gyro_sigma);
  // Sample times t0 + k / rate.
  for (std::size_t k = 0; k < rec.imu.size(); ++k) {
    EXPECT_DOUBLE_EQ(rec.imu[k].t, c.t0 + static_cast<double>(k) / c.imu_rate);
  }
}

}  // namespace
}  // namespace freeinit::sim
