// Trajectory derivatives against central finite differences, preset properties, determinism and
// ground-truth export.
#include <freeinit/sim/presets.h>
#include <freeinit/sim/random_scenario.h>
#include <freeinit/sim/truth_io.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <string>

namespace freeinit::sim {
namespace {

ScenarioConfig shortConfig(const std::string& name, std::uint64_t seed, double duration,
                           int points) {
  ScenarioConfig c = preset(name, seed);
  c.duration = duration;
  c.points_per_frame = points;
  return c;
}

// Central differences with h ~ 1.2e-4 s have truncation error h^2/6 * (third derivative): at most
// ~1.5e-8 * 10 * (2 pi 2.5)^3 / 6 ~ 7e-5 for the 10 rad/s preset's angular acceleration, and
// roundoff ~1e-16 * |x| / h <= 1e-9 (positions up to ~100 m at UNIX-time offsets cancel because
// the trajectory works in t - t0). Tolerance: 2e-4 absolute.
TEST(SimTrajectory, AnalyticDerivativesMatchFiniteDifferences) {
  // h = 2^-13 s and tau = k / 64 s are exact in double at UNIX-time magnitude (whose resolution is
  // 2^-22 s ~ 0.24 us at 1.7e9 s), so t - h, t, t + h are exactly equispaced.
  const double h = 1.0 / 8192.0;
  for (const std::string name : {"dyna_04", "dyna_05", "stat_01", "stat_03", "tunnel_handheld"}) {
    const ScenarioConfig c = shortConfig(name, 1, 5.0, 0);
    const auto traj = makePresetTrajectory(c);
    for (int k = 3; k < 256; k += 11) {
      const double tau = k / 64.0;
      const double t = c.t0 + tau;
      const TruthState s = traj->at(t), sm = traj->at(t - h), sp = traj->at(t + h);
      const Vec3 v_fd = (sp.p_w - sm.p_w) / (2 * h);
      const Vec3 a_fd = (sp.v_w - sm.v_w) / (2 * h);
      const Vec3 w_fd = Eigen::AngleAxisd(sm.R_wb.transpose() * sp.R_wb).angle() *
                        Eigen::AngleAxisd(sm.R_wb.transpose() * sp.R_wb).axis() / (2 * h);
      const Vec3 al_fd = (sp.omega_b - sm.omega_b) / (2 * h);
      EXPECT_LT((s.v_w - v_fd).norm(), 2e-4) << name << " tau " << tau;
      EXPECT_LT((s.a_w - a_fd).norm(), 2e-4) << name << " tau " << tau;
      EXPECT_LT((s.omega_b - w_fd).norm(), 2e-4) << name << " tau " << tau;
      EXPECT_LT((s.alpha_b - al_fd).norm(), 2e-4) << name << " tau " << tau;
      EXPECT_LT((s.R_wb.transpose() * s.R_wb - Mat3::Identity()).norm(), 1e-12);
    }
  }
}

// The randomized motions add a ramped start (ramp_poly), an IMU mounted at tens of degrees and a
// heading, and vibration up to 15 Hz: h = 2^-15 s keeps the truncation error h^2/6 x (third
// derivative) below ~4e-5 (a 3 mm, 15 Hz vibration has a fourth position derivative ~2e5 m/s^4);
// tolerance 2e-4. The instants cover the rest, the blend into motion and the motion.
TEST(SimTrajectory, RandomizedDerivativesMatchFiniteDifferences) {
  const double h = 1.0 / 32768.0;
  for (std::uint64_t seed = 1; seed <= 12; ++seed) {
    const ScenarioConfig c = randomScenario(seed);
    const auto traj = makeTrajectory(c);
    const double blend_end = c.motion.still_until + std::max(c.motion.blend_duration, 0.0);
    for (int k = 1; k < 64; ++k) {
      const double tau = std::round(k / 64.0 * std::max(3.0, blend_end + 0.5) * 1024.0) / 1024.0;
      const double t = c.t0 + tau;
      const TruthState s = traj->at(t), sm = traj->at(t - h), sp = traj->at(t + h);
      const Eigen::AngleAxisd d(sm.R_wb.transpose() * sp.R_wb);
      EXPECT_LT((s.v_w - (sp.p_w - sm.p_w) / (2 * h)).norm(), 2e-4) << seed << " tau " << tau;
      EXPECT_LT((s.a_w - (sp.v_w - sm.v_w) / (2 * h)).norm(), 2e-4) << seed << " tau " << tau;
      EXPECT_LT((s.omega_b - d.angle() * d.axis() / (2 * h)).norm(), 2e-4)
          << seed << " tau " << tau;
      EXPECT_LT((s.alpha_b - (sp.omega_b - sm.omega_b) / (2 * h)).norm(), 2e-4)
          << seed << " tau " << tau;
      EXPECT_LT((s.R_wb.transpose() * s.R_wb - Mat3::Identity()).norm(), 1e-12);
    }
    if (c.motion.blend_duration > 0 && c.motion.still_until > 0.01) {
      const TruthState rest = traj->at(c.t0 + 0.5 * c.motion.still_until);
      EXPECT_EQ(rest.v_w, Vec3::Zero()) << seed;
      EXPECT_EQ(rest.omega_b, Vec3::Zero()) << seed;
    }
  }
}

// A ramped start from rest reaches the cruise speed without overshooting it: the speed is
// S(x) times the polynomial's rate (here constant), never more.
TEST(SimTrajectory, RampedStartDoesNotOvershoot) {
  ScenarioConfig c = preset("stat_02", 1);
  c.motion.pos[0].waves.clear();
  c.motion.pos[1].waves.clear();
  c.motion.ramp_poly = true;
  c.motion.still_until = 0.5;
  c.motion.blend_duration = 2.0;
  const auto traj = makeTrajectory(c);
  double v_max = 0;
  for (double tau = 0; tau < 4.0; tau += 0.01)
    v_max = std::max(v_max, traj->at(c.t0 + tau).v_w.x());
  EXPECT_NEAR(v_max, 1.5, 1e-9);              // stat_02 cruises at 1.5 m/s
  const double t = c.t0 + 1.1;                // 30 % into the blend (S = 0.163)
  const double x = ((t - c.t0) - 0.5) / 2.0;  // as rounded at UNIX-time magnitude
  EXPECT_NEAR(traj->at(t).v_w.x(), 1.5 * (10 - 15 * x + 6 * x * x) * x * x * x, 1e-12);
  // The position after the blend: the integral of S is half the blend, so the platform is
  // 1.5 m/s x (tau - 0.5 - 1.0) along.
  EXPECT_NEAR(traj->at(c.t0 + 3.5).p_w.x() - traj->at(c.t0).p_w.x(), 1.5 * 2.0, 1e-9);
}

TEST(SimTrajectory, EveryPresetGenerates) {
  EXPECT_EQ(presetNames().size(), 13u);
  for (const std::string& name : presetNames()) {
    const Recording rec = simulate(shortConfig(name, 2, 0.3, 3000));
    EXPECT_EQ(rec.frames.size(), 3u) << name;
    EXPECT_EQ(rec.imu.size(), 61u) << name;
    for (const LidarFrame& fr : rec.frames) EXPECT_GT(fr.points.size(), 1000u) << name;
    // Non-level start, non-trivial extrinsics.
    const Vec3 z_b_in_w = rec.truth(rec.config.t0).R_wb.col(2);
    EXPECT_GT(std::acos(z_b_in_w.z()), 1.0 * M_PI / 180.0) << name;
    EXPECT_GT(Eigen::AngleAxisd(rec.extrinsics.R_bl).angle(), 3.0 * M_PI / 180.0);
    EXPECT_GT(rec.extrinsics.p_bl.norm(), 0.1);
  }
  EXPECT_THROW(preset("nope"), std::invalid_argument);
  ScenarioConfig bad = preset("dyna_01");
  bad.name = "nope";
  EXPECT_THROW(simulate(bad), std::invalid_argument);
}

TEST(SimTrajectory, StationaryPresetsStandExactlyStill) {
  for (const std::string name : {"stat_01", "stat_02", "stat_03", "stat_04"}) {
    const ScenarioConfig c = shortConfig(name, 1, 4.0, 0);
    const auto traj = makePresetTrajectory(c);
    const TruthState s0 = traj->at(c.t0);
    for (double tau = 0; tau <= 1.0; tau += 0.005) {
      const TruthState s = traj->at(c.t0 + tau);
      EXPECT_EQ(s.v_w, Vec3::Zero()) << name;
      EXPECT_EQ(s.a_w, Vec3::Zero()) << name;
      EXPECT_EQ(s.omega_b, Vec3::Zero()) << name;
      EXPECT_EQ(s.alpha_b, Vec3::Zero()) << name;
      EXPECT_EQ(s.p_w, s0.p_w) << name;
    }
    // ... and then actually move.
    EXPECT_GT(traj->at(c.t0 + 3.5).v_w.norm(), 0.5) << name;
  }
}

TEST(SimTrajectory, PresetMotionFeatures) {
  auto peak_omega = [](const std::string& name) {
    const ScenarioConfig c = preset(name, 1);
    const auto traj = makePresetTrajectory(c);
    double w = 0;
    for (double tau = 0; tau <= 0.5; tau += 0.001)
      w = std::max(w, traj->at(c.t0 + tau).omega_b.norm());
    return w;
  };
  EXPECT_GE(peak_omega("dyna_04"), 9.0);
  EXPECT_GE(peak_omega("dyna_01"), 4.5);
  EXPECT_GE(peak_omega("dyna_02"), 4.5);
  const auto speed = [](const std::string& name, double tau) {
    const ScenarioConfig c = preset(name, 1);
    return makePresetTrajectory(c)->at(c.t0 + tau).v_w.norm();
  };
  for (double tau = 0; tau <= 1.0; tau += 0.1) {
    EXPECT_NEAR(speed("dyna_05", tau), 75.0 / 3.6, 0.5);
    EXPECT_NEAR(speed("dyna_06", tau), 60.0 / 3.6, 0.5);
    EXPECT_NEAR(speed("tunnel_wheeled", tau), 6.5, 0.3);
    EXPECT_NEAR(speed("tunnel_vehicular", tau), 17.0, 0.5);
    EXPECT_NEAR(speed("dyna_03", tau), 5.0, 0.6);
  }
}

TEST(SimDeterminism, SameSeedSameOutputDifferentSeedDifferent) {
  const ScenarioConfig c = shortConfig("dyna_01", 7, 0.3, 5000);
  const Recording a = simulate(c), b = simulate(c);
  ASSERT_EQ(a.imu.size(), b.imu.size());
  for (std::size_t k = 0; k < a.imu.size(); ++k) {
    EXPECT_EQ(a.imu[k].gyro, b.imu[k].gyro);
    EXPECT_EQ(a.imu[k].accel, b.imu[k].accel);
  }
  ASSERT_EQ(a.frames.size(), b.frames.size());
  for (std::size_t f = 0; f < a.frames.size(); ++f) {
    ASSERT_EQ(a.frames[f].points.size(), b.frames[f].points.size());
    for (std::size_t i = 0; i < a.frames[f].points.size(); ++i) {
      const DopplerPoint &p = a.frames[f].points[i], &q = b.frames[f].points[i];
      EXPECT_EQ(p.p_l, q.p_l);
      EXPECT_EQ(p.doppler, q.doppler);
      EXPECT_EQ(p.time_offset, q.time_offset);
      EXPECT_EQ(p.line, q.line);
      EXPECT_EQ(a.labels[f][i], b.labels[f][i]);
    }
  }
  EXPECT_EQ(a.b_g, b.b_g);
  EXPECT_EQ(a.extrinsics.R_bl, b.extrinsics.R_bl);

  ScenarioConfig c2 = c;
  c2.seed = 8;
  const Recording d = simulate(c2);
  EXPECT_NE(a.b_g, d.b_g);
  EXPECT_NE(a.b_a, d.b_a);
  EXPECT_NE(a.extrinsics.p_bl, d.extrinsics.p_bl);
  EXPECT_NE(a.imu[10].gyro, d.imu[10].gyro);
  EXPECT_NE(a.frames[0].points[100].doppler, d.frames[0].points[100].doppler);
}

TEST(SimTruthIo, WritesTumAndCsv) {
  const ScenarioConfig c = shortConfig("dyna_03", 1, 1.0, 0);
  const auto traj = makePresetTrajectory(c);
  const std::string tum = testing::TempDir() + "sim_truth.tum";
  const std::string csv = testing::TempDir() + "sim_truth.csv";
  writeTumPoses(*traj, c.t0, c.t0 + 1.0, 100.0, tum);
  writeTruthCsv(*traj, c.t0, c.t0 + 1.0, 50.0, csv);
  std::ifstream in(tum);
  int lines = 0;
  double t, x, y, z, qx, qy, qz, qw;
  while (in >> t >> x >> y >> z >> qx >> qy >> qz >> qw) {
    const TruthState s = traj->at(t);
    EXPECT_NEAR(x, s.p_w.x(), 1e-9);
    EXPECT_NEAR(Quat(qw, qx, qy, qz).angularDistance(Quat(s.R_wb)), 0.0, 1e-9);
    ++lines;
  }
  EXPECT_EQ(lines, 101);
  std::ifstream in2(csv);
  std::string line;
  int n = 0;
  while (std::getline(in2, line)) ++n;
  EXPECT_EQ(n, 52);  // header + 51 samples
  std::remove(tum.c_str());
  std::remove(csv.c_str());
}

}  // namespace
}  // namespace freeinit::sim
