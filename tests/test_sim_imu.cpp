// Integrating the simulated IMU (true biases removed, noise off) from the true initial state must
// reproduce the ground-truth pose to within the integration error of the scheme.
#include <freeinit/sim/presets.h>
#include <gtest/gtest.h>

#include <cmath>

#include "test_sim_imu_integration.h"

namespace freeinit::sim {
namespace {

using test::integrate;
using test::IntegrationError;

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
