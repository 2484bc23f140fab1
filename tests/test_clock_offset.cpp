// The LiDAR-IMU clock offset with the default configuration: an offset nobody declared, up to
// 10 ms either way, on randomized scenarios apart from every evaluation range (seeds 6001 on,
// frames capped to 20,000 points): a moving start estimates it and its state stays within 3x its
// bound; a static start keeps it at its prior, and says so.
#include <freeinit/eval/bound_ratio.h>
#include <freeinit/free_init.h>
#include <freeinit/sim/evaluation.h>
#include <freeinit/sim/random_scenario.h>
#include <freeinit/sim/simulator.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "random_runs.h"

namespace freeinit {
namespace {

using OffsetRun = test::RandomRun;

/// The first `count` seeds from 6001 on whose start is `start` ("moving", "static") with the
/// calibration declared right.
std::vector<std::uint64_t> seedsOf(const std::string& start, int count) {
  std::vector<std::uint64_t> seeds;
  for (std::uint64_t seed = 6001; seed < 6400 && static_cast<int>(seeds.size()) < count; ++seed) {
    const sim::RandomScenario sc = sim::drawRandomScenario(seed);
    if (sc.info.start == start && !sc.info.calibration_wrong) seeds.push_back(seed);
  }
  return seeds;
}

/// The seed's recording with the LiDAR clock `offset` [s] ahead of the IMU's, undeclared; the
/// configuration's defaults but for the rig's datasheet noise and declared extrinsics.
OffsetRun runWithOffset(std::uint64_t seed, double offset) {
  sim::RandomScenario sc = test::ciScenario(seed);
  sc.config.lidar_time_offset = offset;
  return test::runScenario(sc);
}

/// The state is ok and none of its errors is more than 3x its bound (above the floors).
void expectWithinBound(const OffsetRun& r, const std::string& what) {
  const InitialState& s = r.result.state;
  ASSERT_TRUE(s.ok()) << what << ": " << s.message;
  const sim::InitErrors e = sim::evaluate(s, r.rec);
  const eval::Bound b = sim::cramerRaoBound(r.rec, r.cfg, r.result);
  ASSERT_TRUE(e.valid && b.ok) << what << ": " << b.message;
  const eval::NoticeFloors floors;
  EXPECT_FALSE(eval::confidentlyWrong(e.vel_b, b.velocity, floors.velocity))
      << what << ": velocity " << e.vel_b << " m/s, bound " << b.velocity;
  EXPECT_FALSE(eval::confidentlyWrong(e.gravity_deg, b.gravity_deg, floors.gravity_deg))
      << what << ": gravity " << e.gravity_deg << " deg, bound " << b.gravity_deg;
  EXPECT_FALSE(eval::confidentlyWrong(e.gyro_bias, b.gyro_bias, floors.gyro_bias))
      << what << ": gyro bias " << e.gyro_bias << " rad/s, bound " << b.gyro_bias;
  EXPECT_FALSE(eval::confidentlyWrong(e.accel_bias, b.accel_bias, floors.accel_bias))
      << what << ": accel bias " << e.accel_bias << " m/s^2, bound " << b.accel_bias;
}

TEST(ClockOffset, DefaultEstimatesIt) {
  const FreeInitConfig cfg;
  EXPECT_EQ(cfg.joint.time_offset_sigma, 0.01);
}

TEST(ClockOffset, UndeclaredEightMillisecondsOnAMovingStart) {
  // Issue 44: with the clocks taken as synchronized, an 8 ms offset had two of four moving starts
  // refused and two ok with a warning. By default the offset is estimated with the motion.
  const std::vector<std::uint64_t> seeds = seedsOf("moving", 1);
  ASSERT_EQ(seeds.size(), 1u);
  const OffsetRun r = runWithOffset(seeds[0], 0.008);
  const std::string what = "seed " + std::to_string(seeds[0]) + ", 8 ms";
  expectWithinBound(r, what);
  const InitialState& s = r.result.state;
  EXPECT_TRUE(s.time_offset_estimated) << what << ": sigma " << s.time_offset_sigma;
  EXPECT_GT(s.time_offset_sigma, 0.0);
  EXPECT_LT(std::abs(s.time_offset - 0.008), 3 * s.time_offset_sigma + 2e-4)
      << what << ": " << s.time_offset << " s, sigma " << s.time_offset_sigma;
}

TEST(ClockOffset, MovingStartsFromMinusTenToTenMilliseconds) {
  for (const std::uint64_t seed : seedsOf("moving", 2)) {
    for (const double offset : {0.0, 0.004, -0.004, 0.010, -0.010}) {
      const OffsetRun r = runWithOffset(seed, offset);
      const std::string what =
          "seed " + std::to_string(seed) + ", " + std::to_string(1e3 * offset) + " ms";
      expectWithinBound(r, what);
      const InitialState& s = r.result.state;
      if (s.time_offset_estimated) {
        EXPECT_LT(std::abs(s.time_offset - offset), 3 * s.time_offset_sigma + 2e-4)
            << what << ": " << s.time_offset << " s, sigma " << s.time_offset_sigma;
      }
    }
  }
}

TEST(ClockOffset, AGentleStartDoesNotReadItFromTheImusNoise) {
  // Windows in which the platform starts moving, gently: the acceleration grows from zero to a
  // few 0.1 m/s^2, no more than the accelerometer's noise per sample. The offset's column built
  // from the samples was mostly that noise and read as knowledge of the offset: seed 6006 at
  // -8 ms claimed +6.9 +- 3 ms, and with the IMU's noise removed from the recording the same
  // window gives +-9.4 ms, its prior nearly. Where the offset is estimated it is within 3 sigma;
  // where the motion cannot tell it, it stays near its prior.
  const std::vector<std::uint64_t> seeds = seedsOf("starting", 3);
  ASSERT_EQ(seeds.size(), 3u);
  for (const std::uint64_t seed : seeds) {
    for (const double offset : {0.008, -0.008}) {
      const OffsetRun r = runWithOffset(seed, offset);
      const std::string what =
          "seed " + std::to_string(seed) + ", " + std::to_string(1e3 * offset) + " ms";
      const InitialState& s = r.result.state;
      ASSERT_TRUE(s.ok()) << what << ": " << s.message;
      EXPECT_LT(std::abs(s.time_offset - offset), 3 * s.time_offset_sigma + 2e-4)
          << what << ": " << s.time_offset << " s, sigma " << s.time_offset_sigma
          << (s.time_offset_estimated ? " (estimated)" : " (prior)");
    }
  }
}

TEST(ClockOffset, StaticStartKeepsItsPrior) {
  // At rest the offset moves nothing the returns see: it stays at its prior, and the state says
  // so; the state is the same whatever the offset.
  for (const std::uint64_t seed : seedsOf("static", 1)) {
    for (const double offset : {0.0, 0.010, -0.010}) {
      const OffsetRun r = runWithOffset(seed, offset);
      const std::string what =
          "seed " + std::to_string(seed) + ", " + std::to_string(1e3 * offset) + " ms";
      expectWithinBound(r, what);
      const InitialState& s = r.result.state;
      EXPECT_TRUE(r.result.diag.static_start) << what;
      EXPECT_FALSE(s.time_offset_estimated) << what << ": sigma " << s.time_offset_sigma;
      EXPECT_GT(s.time_offset_sigma, 0.5 * r.cfg.joint.time_offset_sigma) << what;
      EXPECT_LT(std::abs(s.time_offset), 0.5 * r.cfg.joint.time_offset_sigma) << what;
    }
  }
}

TEST(ClockOffset, DeclaredExactIsReportedAsSuch) {
  // time_offset_sigma = 0: the clocks are taken as synchronized, the offset reported as 0 with no
  // uncertainty, at its prior.
  const std::vector<std::uint64_t> seeds = seedsOf("moving", 1);
  ASSERT_EQ(seeds.size(), 1u);
  OffsetRun r = runWithOffset(seeds[0], 0.0);
  r.cfg.joint.time_offset_sigma = 0;
  r.result = FreeInit::run(r.cfg, r.rec.imu, r.rec.frames);
  ASSERT_TRUE(r.result.state.ok()) << r.result.state.message;
  EXPECT_EQ(r.result.state.time_offset, 0.0);
  EXPECT_EQ(r.result.state.time_offset_sigma, 0.0);
  EXPECT_FALSE(r.result.state.time_offset_estimated);
}

}  // namespace
}  // namespace freeinit
