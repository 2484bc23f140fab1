// What the tests on randomized scenarios share: the scenario cut to fit CI, the configuration a
// user of the simulated rig would write, and one run of the estimator with it.
#pragma once

#include <freeinit/free_init.h>
#include <freeinit/sim/random_scenario.h>
#include <freeinit/sim/simulator.h>

#include <algorithm>
#include <cstdint>

namespace freeinit::test {

/// One randomized scenario, its recording, the configuration and the estimator's result.
struct RandomRun {
  sim::RandomScenario scenario;
  sim::Recording rec;
  FreeInitConfig cfg;
  InitResult result;
};

/// The seed's randomized scenario, 0.8 s long with frames capped to 20,000 points (to fit CI).
inline sim::RandomScenario ciScenario(std::uint64_t seed) {
  sim::RandomScenario sc = sim::drawRandomScenario(seed);
  sc.config.duration = 0.8;
  sc.config.points_per_frame = std::min(sc.config.points_per_frame, 20000);
  return sc;
}

/// What a user of the rig configures: the defaults but for the calibration as declared and the
/// datasheet noise, the IMU's times `imu_factor` and the Doppler's times `doppler_factor`.
inline FreeInitConfig rigConfig(const sim::Recording& rec, double imu_factor = 1.0,
                                double doppler_factor = 1.0) {
  FreeInitConfig cfg;
  cfg.extrinsics = rec.declared_extrinsics;
  cfg.doppler.doppler_sigma = doppler_factor * rec.config.doppler_sigma;
  cfg.imu.gyro_sigma = imu_factor * rec.config.gyro_sigma;
  cfg.imu.accel_sigma = imu_factor * rec.config.accel_sigma;
  return cfg;
}

/// `scenario` simulated and initialized with rigConfig(rec, imu_factor, doppler_factor).
inline RandomRun runScenario(const sim::RandomScenario& scenario, double imu_factor = 1.0,
                             double doppler_factor = 1.0) {
  RandomRun r{scenario, {}, {}, {}};
  r.rec = sim::simulate(r.scenario.config);
  r.cfg = rigConfig(r.rec, imu_factor, doppler_factor);
  r.result = FreeInit::run(r.cfg, r.rec.imu, r.rec.frames);
  return r;
}

}  // namespace freeinit::test
