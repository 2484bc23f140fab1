// Filter nodes at a bounded rate ([joint] node_rate): with a 1 kHz IMU and nodes at every fifth
// sample, every sample is still integrated, so the estimate must be the one with a node per
// sample up to a small fraction of what the data resolve (the Cramer-Rao bound of the window).
#include <freeinit/free_init.h>
#include <freeinit/rotation.h>
#include <freeinit/sim/evaluation.h>
#include <freeinit/sim/random_scenario.h>
#include <freeinit/sim/simulator.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace freeinit {
namespace {

/// The first scenario of the development range with a right calibration and the given start
/// ("moving", "static", ...), its IMU at 1 kHz (the per-sample noise at the scenario's density).
sim::ScenarioConfig fastImuScenario(const std::string& start) {
  for (std::uint64_t seed = 8301;; ++seed) {
    const sim::RandomScenario s = sim::drawRandomScenario(seed);
    if (s.info.calibration_wrong || s.info.start != start) continue;
    sim::ScenarioConfig c = s.config;
    c.duration = 1.0;
    c.points_per_frame = 20000;
    const double rate = 1000.0, scale = std::sqrt(rate / c.imu_rate);
    c.gyro_sigma *= scale;
    c.accel_sigma *= scale;
    c.imu_rate = rate;
    return c;
  }
}

void expectSameEstimate(const std::string& start) {
  const sim::ScenarioConfig c = fastImuScenario(start);
  const sim::Recording rec = sim::simulate(c);
  FreeInitConfig cfg;
  cfg.extrinsics = rec.declared_extrinsics;
  cfg.doppler.doppler_sigma = c.doppler_sigma;
  cfg.imu.gyro_sigma = c.gyro_sigma;
  cfg.imu.accel_sigma = c.accel_sigma;
  if (std::getenv("NOLEVER")) cfg.joint.lever_arm_gyro_noise = false;
  if (std::getenv("NOTIME")) cfg.joint.time_offset_sigma = 0;
  const InitResult every = FreeInit::run(cfg, rec.imu, rec.frames);
  cfg.joint.node_rate = std::getenv("NODERATE") ? std::atof(std::getenv("NODERATE")) : 200.0;
  const InitResult fifth = FreeInit::run(cfg, rec.imu, rec.frames);
  ASSERT_TRUE(every.state.ok()) << every.state.message;
  ASSERT_TRUE(fifth.state.ok()) << fifth.state.message;
  // A node at every fifth sample and at the window's last (the last interval may be shorter).
  EXPECT_EQ(fifth.trajectory.size(), (every.trajectory.size() - 1 + 4) / 5 + 1);
  // The same state time (the window's last sample is a node either way).
  EXPECT_EQ(every.state.timestamp, fifth.state.timestamp);
  const eval::Bound b = sim::cramerRaoBound(rec, cfg, every);
  ASSERT_TRUE(b.ok) << b.message;
  const InitialState &x = every.state, &y = fifth.state;
  const Vec3 g_x = x.g_b(), g_y = y.g_b();
  const double gravity_deg = std::acos(std::min(1.0, g_x.normalized().dot(g_y.normalized()))) *
                             180.0 / 3.14159265358979323846;
  const double dv = (x.v_b() - y.v_b()).norm() / b.velocity;
  const double dg = gravity_deg / b.gravity_deg;
  const double dbg = (x.b_g - y.b_g).norm() / b.gyro_bias;
  const double dba = (x.b_a - y.b_a).norm() / b.accel_bias;
  const sim::InitErrors ex = sim::evaluate(x, rec), ey = sim::evaluate(y, rec);
  std::printf("%s: error / bound, node per sample: velocity %.3f b_g %.3f; every fifth: %.3f %.3f\n",
              start.c_str(), ex.vel_b / b.velocity, ex.gyro_bias / b.gyro_bias,
              ey.vel_b / b.velocity, ey.gyro_bias / b.gyro_bias);
  std::printf("used %zu %zu rejected %zu %zu iterations %d %d rms %.5f %.5f\n", every.diag.points_used,
              fifth.diag.points_used, every.diag.points_rejected, fifth.diag.points_rejected,
              every.diag.iterations, fifth.diag.iterations, every.diag.doppler_residual_rms,
              fifth.diag.doppler_residual_rms);
  if (std::getenv("TRACE"))
    for (std::size_t i = 0; i < fifth.velocities.size(); ++i) {
      const VelocitySample& f = fifth.velocities[i];
      for (const VelocitySample& e : every.velocities)
        if (e.t == f.t) {
          const Vec3 tv = rec.truth(f.t).R_wb.transpose() * rec.truth(f.t).v_w;
          std::printf("t %.4f dv %.5f  err every %.5f fifth %.5f  dbg %.6f\n", f.t - every.velocities[0].t, (e.v_b - f.v_b).norm(), (e.v_b-tv).norm(), (f.v_b-tv).norm(), (e.b_g - f.b_g).norm());
        }
    }
  std::printf("%s: difference / bound: velocity %.3f gravity %.3f b_g %.3f b_a %.3f\n",
              start.c_str(), dv, dg, dbg, dba);
  EXPECT_LT(dv, 0.1);
  EXPECT_LT(dg, 0.1);
  EXPECT_LT(dbg, 0.1);
  EXPECT_LT(dba, 0.1);
}

TEST(NodeRate, MovingStartWithAFastImuGivesTheSameEstimate) { expectSameEstimate("moving"); }

TEST(NodeRate, StaticStartWithAFastImuGivesTheSameEstimate) { expectSameEstimate("static"); }

}  // namespace
}  // namespace freeinit
