// The estimator on randomized scenarios it was not tuned on (a fixed subset of seeds apart from
// the ranges used while developing it and from the held-out evaluation), with frames capped to
// 20,000 points to fit CI: no ok state far outside its physical limit, its own covariance
// consistent with its errors, a static start among walkers in an open scene at rest, and standing
// sensors among movers with a consistent velocity.
#include <freeinit/eval/bound_ratio.h>
#include <freeinit/eval/cramer_rao_bound.h>
#include <freeinit/free_init.h>
#include <freeinit/sim/evaluation.h>
#include <freeinit/sim/random_scenario.h>
#include <freeinit/sim/simulator.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <string>

#include "random_runs.h"

namespace freeinit {
namespace {

using test::RandomRun;

/// The seed's scenario with what a user of the rig configures: the datasheet noise and the
/// calibration as declared.
RandomRun runSeed(std::uint64_t seed) { return test::runScenario(test::ciScenario(seed)); }

TEST(FreeInitRandomized, NoConfidentWrongStateAndAConsistentCovariance) {
  constexpr std::uint64_t kFirst = 7001, kRuns = 30;
  const eval::NoticeFloors floors;
  // NEES above the 99.9 % chi-square quantile (3 dof: 16.27, the tilt's 2 dof: 13.82), per block
  // (velocity, tilt, b_g, b_a).
  const std::array<double, 4> quantile = {16.27, 13.82, 16.27, 16.27};
  std::array<int, 4> above{};
  int ok = 0, declined = 0;
  for (std::uint64_t seed = kFirst; seed < kFirst + kRuns; ++seed) {
    const RandomRun r = runSeed(seed);
    // A wrong declared calibration is judged by the evaluation's warnings, not here.
    if (r.scenario.info.calibration_wrong) continue;
    const InitialState& s = r.result.state;
    if (!s.ok()) {
      // Declining is allowed (the start may be ambiguous, the data inconsistent), never a crash
      // or an unexplained refusal.
      EXPECT_FALSE(s.message.empty()) << "seed " << seed;
      ++declined;
      continue;
    }
    ++ok;
    const sim::InitErrors e = sim::evaluate(s, r.rec);
    const eval::Bound b = sim::cramerRaoBound(r.rec, r.cfg, r.result);
    ASSERT_TRUE(e.valid && b.ok) << "seed " << seed << ": " << b.message;
    const std::string what = "seed " + std::to_string(seed) + " (" +
                             sim::platformName(r.scenario.info.platform) + "/" +
                             r.scenario.info.start + ")";
    EXPECT_FALSE(eval::confidentlyWrong(e.vel_b, b.velocity, floors.velocity)) << what;
    EXPECT_FALSE(eval::confidentlyWrong(e.gravity_deg, b.gravity_deg, floors.gravity_deg)) << what;
    EXPECT_FALSE(eval::confidentlyWrong(e.gyro_bias, b.gyro_bias, floors.gyro_bias)) << what;
    EXPECT_FALSE(eval::confidentlyWrong(e.accel_bias, b.accel_bias, floors.accel_bias)) << what;
    const std::array<double, 4> nees = {e.nees_vel_b, e.nees_tilt, e.nees_gyro_bias,
                                        e.nees_accel_bias};
    for (std::size_t k = 0; k < 4; ++k)
      if (!(nees[k] <= quantile[k])) ++above[k];
  }
  std::printf(
      "%d ok, %d declined; NEES above the 99.9 %% quantile: v %d, tilt %d, b_g %d, b_a %d\n", ok,
      declined, above[0], above[1], above[2], above[3]);
  // Most of these starts can be initialized: the held-out evaluation declines 2 % of those with a
  // right calibration (4 or more of ~22 would happen with probability < 1 %).
  EXPECT_GE(ok, 15);
  EXPECT_LE(declined, 3);
  // A consistent estimator exceeds the 99.9 % quantile in 0.1 % of the runs; at the 1 % the
  // estimator is held to, 3 or more of ~25 happen with probability 0.2 %.
  for (std::size_t k = 0; k < 4; ++k) EXPECT_LE(above[k], 2) << "block " << k;
}

// A person 1.4 m from a handheld rig that moves at 0.7 m/s (seed 5000040, once of a held-out
// evaluation: its only confident wrong answer): 16 % of the returns are on the person, a third of
// them move slowly enough along their line of sight to pass every gate, and together they moved
// the velocity by 0.05 m/s, 7.7x its bound (NEES 162). Within 50 ms the person keeps its
// directions, and there its returns share a non-zero residual: they leave the estimate (0.009
// m/s, NEES 5). Without the person, no residual warning; with the Doppler noise configured 10 %
// below the simulator's, the estimator uses the noise its returns show.
TEST(FreeInitRandomized, MoverCloseToAMovingRigLeavesTheEstimate) {
  RandomRun r = runSeed(5000040);
  ASSERT_FALSE(r.scenario.info.calibration_wrong);
  ASSERT_GT(sim::movingPointShare(r.rec), 0.1) << "the scenario drawn for this seed changed";
  auto warnsOfResiduals = [](const InitialState& s) {
    return std::any_of(s.warnings.begin(), s.warnings.end(), [](const std::string& w) {
      return w.find("by more than chance allows") != std::string::npos;
    });
  };
  ASSERT_TRUE(r.result.state.ok()) << r.result.state.message;
  const sim::InitErrors with_person = sim::evaluate(r.result.state, r.rec);
  EXPECT_LT(with_person.vel_b, 0.02);
  EXPECT_LT(with_person.nees_vel_b, 16.27);

  r.scenario.config.scene.objects.clear();
  r.rec = sim::simulate(r.scenario.config);
  ASSERT_LT(sim::movingPointShare(r.rec), 0.01);
  r.result = FreeInit::run(r.cfg, r.rec.imu, r.rec.frames);
  ASSERT_TRUE(r.result.state.ok()) << r.result.state.message;
  EXPECT_FALSE(warnsOfResiduals(r.result.state));
  EXPECT_LT(sim::evaluate(r.result.state, r.rec).nees_vel_b, 16.27);

  // The noise configured 10 % low: the estimator reads it from the returns' residuals (tens of
  // thousands: to well under 1 %, the gates' cut corrected) and uses that, so that the residuals
  // no longer exceed it and the velocity stays consistent.
  r.cfg.doppler.doppler_sigma = 0.9 * r.rec.config.doppler_sigma;
  r.result = FreeInit::run(r.cfg, r.rec.imu, r.rec.frames);
  ASSERT_TRUE(r.result.state.ok()) << r.result.state.message;
  EXPECT_FALSE(warnsOfResiduals(r.result.state));
  EXPECT_EQ(r.result.diag.noise.doppler.source, NoiseUsed::Source::Data);
  EXPECT_NEAR(r.result.diag.noise.doppler.value / r.rec.config.doppler_sigma, 1.0, 0.03);
  EXPECT_LT(sim::evaluate(r.result.state, r.rec).nees_vel_b, 16.27);
}

// A wheeled robot that starts to roll so gently (a 5 s ramp from 0.05 s on, seed 6000132, once of
// a held-out evaluation) that the accelerometer shows rest through the whole window while the
// Doppler of 50,000 returns sees 0.02 m/s: held at rest, the velocity came out 0.005 m/s off at
// 7x its sigma (NEES 57). The returns contradict the rest, which is withdrawn, and the state says
// so. The same robot standing still keeps its rest.
TEST(FreeInitRandomized, StartTooGentleForTheAccelerometerIsSeenInTheDoppler) {
  RandomRun r = runSeed(6000132);
  ASSERT_FALSE(r.scenario.info.calibration_wrong);
  ASSERT_LT(r.rec.config.motion.still_until, 0.1) << "the scenario drawn for this seed changed";
  ASSERT_GT(r.rec.config.motion.blend_duration, 3.0) << "the scenario drawn for this seed changed";
  auto withdrawn = [](const InitialState& s) {
    return std::any_of(s.warnings.begin(), s.warnings.end(), [](const std::string& w) {
      return w.find("the IMU showed rest through the window") != std::string::npos;
    });
  };
  ASSERT_TRUE(r.result.state.ok()) << r.result.state.message;
  EXPECT_TRUE(r.result.diag.static_start);  // what the start decision saw
  EXPECT_TRUE(withdrawn(r.result.state));
  const sim::InitErrors moving = sim::evaluate(r.result.state, r.rec);
  EXPECT_GT(moving.vel_b_true_norm, 0.015);
  EXPECT_LT(moving.nees_vel_b, 16.27);
  // Only the zero velocity is withdrawn: the gyro, which showed no rotation, still measures its
  // bias, to within 3x the bound of an estimator that knows the rate is zero over the window
  // (without it, the error was 18-58x that bound on such starts of a held-out evaluation).
  EXPECT_EQ(r.result.diag.static_duration, 0.0);
  EXPECT_GT(r.result.diag.zero_rate_duration, 0.4);
  const double zero_rate = eval::zeroRateGyroBiasBound(
      r.rec.config.gyroSigmaPerAxis(), r.result.trajectory.size(), r.cfg.imu.gyro_bias_sigma0);
  EXPECT_LT(moving.gyro_bias, 3 * zero_rate) << "zero-rate bound " << zero_rate << " rad/s";

  r.scenario.config.motion.still_until = 100;  // standing still throughout
  r.rec = sim::simulate(r.scenario.config);
  r.result = FreeInit::run(r.cfg, r.rec.imu, r.rec.frames);
  ASSERT_TRUE(r.result.state.ok()) << r.result.state.message;
  EXPECT_FALSE(withdrawn(r.result.state));
  EXPECT_GT(r.result.diag.static_duration, 0.4);
  const sim::InitErrors still = sim::evaluate(r.result.state, r.rec);
  EXPECT_LT(still.vel_b, 0.002);
  EXPECT_LT(still.nees_vel_b, 16.27);
}

// What moves cannot be told from the Doppler and the IMU alone when a moving object fills the view;
// two such starts of held-out evaluations came out ok and wrong. A handheld sensor walking at
// 1.6 m/s past a box truck that drives at 5.6 m/s 6 m away and covers 93 % of the view (seed
// 44000300): the world showed only on the ground, and the state was the truck's frame, 5.6 m/s
// off; it is declined, saying why. A handheld sensor standing among walkers who make 96 % of the
// returns (seed 44700290): the IMU at rest throughout, the state followed the walkers, 1.8 m/s
// off, and was then declined as ambiguous. Which way it goes is decided by the window's first
// node, before any rest is known, where the walkers' returns move the state (and the clock
// offset by four times its prior): a reference offset that followed the filter kept the standing
// sensor, one held at the prior until the first smoothing declines it, naming moving objects.
// What must hold either way: it is not ok and wrong. A handheld start among walkers whose
// returns make 90 % of the view (seed 45000206, once of a held-out evaluation): the state
// followed them after the start, 0.29 m/s off at a NEES of 2000 with the Doppler noise read from
// the residuals (so they looked right); it is declined, as only a tenth of the returns agree with
// it and even those do not fit it.
TEST(FreeInitRandomized, AMovingObjectFillingTheViewIsNotTakenForTheWorld) {
  const RandomRun truck = runSeed(44000300);
  ASSERT_EQ(truck.scenario.info.start, "moving") << "the scenario drawn for this seed changed";
  EXPECT_EQ(truck.result.state.status, InitStatus::AmbiguousMotion) << truck.result.state.message;
  EXPECT_NE(truck.result.state.message.find("ground"), std::string::npos)
      << truck.result.state.message;
  const RandomRun walkers = runSeed(45000206);
  ASSERT_EQ(walkers.scenario.info.start, "starting") << "the scenario drawn for this seed changed";
  EXPECT_EQ(walkers.result.state.status, InitStatus::AmbiguousMotion)
      << walkers.result.state.message;
  EXPECT_NE(walkers.result.state.message.find("moving objects"), std::string::npos)
      << walkers.result.state.message;
  const RandomRun crowd = runSeed(44700290);
  ASSERT_EQ(crowd.scenario.info.start, "static") << "the scenario drawn for this seed changed";
  if (!crowd.result.state.ok()) {
    EXPECT_NE(crowd.result.state.message.find("moving objects"), std::string::npos)
        << crowd.result.state.message;
    return;
  }
  EXPECT_GT(crowd.result.diag.static_duration, 0.4);
  const sim::InitErrors e = sim::evaluate(crowd.result.state, crowd.rec);
  const eval::Bound b = sim::cramerRaoBound(crowd.rec, crowd.cfg, crowd.result);
  ASSERT_TRUE(e.valid && b.ok) << b.message;
  EXPECT_LT(e.vel_b, 3 * b.velocity);
  EXPECT_LT(e.nees_vel_b, 16.27);
}

// A car at 15.5 m/s, turning at 0.02 rad/s, its LiDAR-IMU rotation declared 1.1 deg off (seed
// 8000246, once of a held-out evaluation: its only plain ok that was wrong). Driving nearly
// straight, the returns fit the rotated velocity as well as the true one (residual RMS 0.98
// sigma both ways): the velocity came out 0.26 m/s off while the calibration test, vouched for by
// the start's velocity prior (measured with the same returns and the wrong rotation), read the
// rotation to 0.03 deg. Without that prior in the test, the state says that this motion does
// not check the calibration, with the declared rotation and with the true one alike.
TEST(FreeInitRandomized, DrivingStraightDoesNotVouchForTheCalibration) {
  RandomRun r = runSeed(8000246);
  ASSERT_TRUE(r.scenario.info.calibration_wrong);
  ASSERT_GT(r.scenario.info.rotation_error_deg, 0.5) << "the scenario drawn for this seed changed";
  auto uncheckedOrOff = [](const InitialState& s) {
    return std::any_of(s.warnings.begin(), s.warnings.end(), [](const std::string& w) {
      return w.find("does not check the LiDAR-IMU calibration") != std::string::npos ||
             w.find("calibration is off") != std::string::npos;
    });
  };
  ASSERT_TRUE(r.result.state.ok()) << r.result.state.message;
  const sim::InitErrors e = sim::evaluate(r.result.state, r.rec);
  EXPECT_GT(e.vel_b, 0.1) << "the wrong rotation no longer moves the velocity: the test is moot";
  EXPECT_TRUE(uncheckedOrOff(r.result.state));

  r.cfg.extrinsics = r.rec.extrinsics;
  r.result = FreeInit::run(r.cfg, r.rec.imu, r.rec.frames);
  ASSERT_TRUE(r.result.state.ok()) << r.result.state.message;
  EXPECT_LT(sim::evaluate(r.result.state, r.rec).vel_b, 0.01);
  EXPECT_TRUE(uncheckedOrOff(r.result.state));
}

TEST(FreeInitRandomized, StaticStartAmongWalkersInTheOpen) {
  // The first randomized seeds (outside every evaluation range) that draw a static start in an
  // open scene with people walking in view: the state is one of rest, the walkers do not move it.
  int found = 0;
  for (std::uint64_t seed = 9001; seed < 9400 && found < 2; ++seed) {
    const sim::RandomScenario sc = sim::drawRandomScenario(seed);
    if (!sc.info.static_start || sc.info.movers_in_view == 0 || sc.info.scene != "open" ||
        sc.info.calibration_wrong)
      continue;
    ++found;
    const RandomRun r = runSeed(seed);
    ASSERT_TRUE(r.result.state.ok()) << "seed " << seed << ": " << r.result.state.message;
    EXPECT_TRUE(r.result.diag.static_start) << "seed " << seed;
    const sim::InitErrors e = sim::evaluate(r.result.state, r.rec);
    // At rest the Doppler of ~100,000 static returns pins the velocity to ~1 mm/s; walkers taken
    // for the world would show as tenths of a m/s.
    EXPECT_LT(e.vel_b, 0.01) << "seed " << seed;
  }
  EXPECT_EQ(found, 2);
}

TEST(FreeInitRandomized, StandingSensorAmongMoversHasAConsistentVelocity) {
  // People or vehicles moving by a standing sensor: each of their returns that moves slowly along
  // its line of sight passes every gate, and together they bend the velocity by a few mm/s,
  // several of its sigmas (without the estimator's test of such returns by direction and range,
  // 3 of these 24 starts have a velocity NEES of 19-56). The first 24 seeds (outside every
  // evaluation range) that draw a static start with movers in view and a right calibration: a
  // consistent estimator exceeds the 99.9 % quantile of the NEES (3 dof) in 0.1 % of the runs,
  // twice or more in 24 with probability 0.03 %.
  int found = 0, above = 0;
  for (std::uint64_t seed = 9001; seed < 10000 && found < 24; ++seed) {
    const sim::RandomScenario sc = sim::drawRandomScenario(seed);
    if (!sc.info.static_start || sc.info.movers_in_view == 0 || sc.info.calibration_wrong) continue;
    ++found;
    const RandomRun r = runSeed(seed);
    const std::string what = "seed " + std::to_string(seed) + " (" +
                             sim::platformName(r.scenario.info.platform) + ", " +
                             r.scenario.info.scene + ")";
    if (!r.result.state.ok()) {
      EXPECT_FALSE(r.result.state.message.empty()) << what;
      continue;
    }
    const sim::InitErrors e = sim::evaluate(r.result.state, r.rec);
    ASSERT_TRUE(e.valid) << what;
    if (e.nees_vel_b > 16.27) {
      ++above;
      std::printf("%s: velocity error %.4f m/s, NEES %.1f\n", what.c_str(), e.vel_b, e.nees_vel_b);
    }
  }
  EXPECT_EQ(found, 24);
  EXPECT_LE(above, 1);
}

}  // namespace
}  // namespace freeinit
