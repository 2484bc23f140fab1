// Checks a whole recording before it is used, so that bad input fails loudly with the file, the
// record index and what is wrong, instead of producing a confident wrong answer.
#pragma once

#include <freeinit/mrpt/app_config.h>
#include <freeinit/mrpt/rawlog_reader.h>
#include <freeinit/types.h>

#include <optional>
#include <string>
#include <vector>

namespace freeinit::mrpt_glue {

/// The recording in core types, as the estimator will see it.
struct ValidatedInput {
  std::vector<ImuSample> imu;
  std::vector<LidarFrame> frames;
  std::optional<Extrinsics> sensor_pose_extrinsics;  ///< LiDAR sensorPose relative to the IMU's
  std::size_t invalid_points_dropped = 0;
  std::vector<std::string> warnings;
};

// Checks shared by the offline validator and the live FreeInitObservationHandler, so that both
// refuse the same input. Each returns what is wrong (without file or record), or nothing.

/// Samples whose mean judges the accelerometer unit, and (live) the IMU rate before any is used.
inline constexpr std::size_t kImuCheckSamples = 200;
/// What the observation handler checks before it feeds the estimator (0.1 s at 200 Hz): enough
/// for the rate and for g vs m/s^2 (a mean of 1 g vs 9.81), few enough to keep latency low.
inline constexpr std::size_t kLiveImuCheckSamples = 20;
/// Doppler zero (or non-finite) for every point: an ego-motion-compensated or Doppler-less sensor.
std::optional<std::string> dopplerProblem(const std::vector<DopplerPoint>& points);
/// Median-interval rate of `imu` (>= 2 samples) below `min_rate` [Hz].
std::optional<std::string> imuRateProblem(const std::vector<ImuSample>& imu, double min_rate);
/// The mean of the first kImuCheckSamples accelerations (already scaled by the declared unit)
/// says the declared unit ([input] imu_accel_in_g) is wrong.
std::optional<std::string> accelUnitProblem(const std::vector<ImuSample>& imu, bool declared_g);

/// Throws InputError for: no IMU or no LiDAR observations with the configured labels, IMU without
/// gyro/accel fields, clouds without Doppler (any class but CPointsMapDoppler), empty clouds,
/// NaN/inf points (unless [input] drop_invalid_points), timestamps going backwards or duplicated,
/// an IMU slower than [input] min_imu_rate, accelerations in g without [input] imu_accel_in_g
/// (or the reverse), Doppler zero everywhere, a recording shorter than the window.
ValidatedInput validateInput(const std::vector<RawlogRecord>& records, const AppConfig& config,
                             const std::string& file);

}  // namespace freeinit::mrpt_glue
