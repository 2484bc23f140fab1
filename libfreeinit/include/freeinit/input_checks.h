// Checks of input data before the estimator uses them, the same whichever way the data come in
// (rawlog reader, live stream, bag importer) and the ones FreeInit itself enforces. Each check
// returns what is wrong as one sentence without file or record (the caller names those), or
// nothing. No I/O, no MRPT.
//
// Per record: an IMU sample (finite, time increasing), a LiDAR frame (points valid, stamp
// increasing, points sorted in time and not reaching back into the previous frame).
// Per stretch of a window: the IMU rate, the accelerometer unit, and whether the IMU shows rest
// where a frame has Doppler exactly zero on every point (legitimate at rest for a sensor with
// quantized Doppler; ego-motion-compensated Doppler otherwise).
#pragma once

#include <freeinit/config.h>
#include <freeinit/types.h>

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace freeinit::input {

/// IMU samples whose mean specific force judges the accelerometer unit (whole recordings).
inline constexpr std::size_t kRecordingImuCheckSamples = 200;
/// IMU samples a window's rate and unit checks use before the estimator sees any data (0.1 s at
/// 200 Hz): enough for the rate and for g vs m/s^2 (a mean of 1 vs 9.81), few enough that a live
/// estimator keeps up with the stream from early on.
inline constexpr std::size_t kWindowImuCheckSamples = 20;
/// [s] IMU samples this close to a frame's points judge whether the platform was at rest.
inline constexpr double kRestMargin = 0.05;

/// "1700000000.123456": UNIX stamps with enough digits to tell neighbouring samples apart.
std::string formatStamp(double t);

/// Not finite, or its time not after `previous`'s (when given).
std::optional<std::string> imuSampleProblem(const ImuSample& s, const ImuSample* previous);

/// A point with a non-finite coordinate, Doppler or time offset.
bool invalidPoint(const DopplerPoint& p);

/// Sorts the points by time offset (stably) unless they already are, as every source delivers
/// frames to the estimator.
void sortByTime(LidarFrame& f);

/// Times [UNIX s] of a frame's first and last point (the stamp for both when it has none).
struct FrameSpan {
  double begin = 0, end = 0;
};
FrameSpan frameSpan(const LidarFrame& f);

/// What the estimator requires of a frame after the previous ones: a finite stamp after
/// `previous_stamp`, finite time offsets sorted in time, and a first point not before
/// `previous_end` (the last point time of the last frame with points).
std::optional<std::string> frameOrderProblem(const LidarFrame& f,
                                             const std::optional<double>& previous_stamp,
                                             const std::optional<double>& previous_end);

/// No point with a finite, non-zero Doppler.
bool dopplerAllZero(const std::vector<DopplerPoint>& points);

/// Median-interval rate of `imu` (>= 2 samples) below `min_rate` [Hz].
std::optional<std::string> imuRateProblem(const std::vector<ImuSample>& imu, double min_rate);
/// The mean of the first kRecordingImuCheckSamples accelerations (already scaled by the declared
/// unit) says the declared unit ([input] imu_accel_in_g) is wrong.
std::optional<std::string> accelUnitProblem(const std::vector<ImuSample>& imu, bool declared_g);

/// Thresholds of the rest test, from the estimator's configuration.
struct RestParams {
  double max_gyro_dev = 0.03;           ///< [rad/s] gyro deviation from its mean ([paper_rest])
  double max_gyro_bias = 0.075;         ///< [rad/s] |mean gyro - prior| (max_gyro_dev + 3 sigma0)
  Vec3 gyro_bias_prior = Vec3::Zero();  ///< [rad/s]
  double max_accel_dev = 0.3;           ///< [m/s^2] specific-force deviation from its mean
  double max_accel_bias = 0.87;         ///< [m/s^2] ||mean f| - g| (the bias bound on each axis)
};
/// max_gyro_dev from [paper_rest]; the gyro bias bound as the paper's static start detector's;
/// the accelerometer deviation max(0.3, 6 accel_sigma); ||f| - g| within sqrt(3) bias bounds.
RestParams restParams(const FreeInitConfig& config);

/// Why `imu` (the samples within kRestMargin of a frame's points) is not consistent with rest,
/// or nothing when it is: the gyro and the specific force are constant within the noise, the
/// gyro near its bias and the specific force near 1 g. Fewer than 2 samples cannot tell.
std::optional<std::string> motionProblem(const std::vector<ImuSample>& imu, const RestParams& p);

/// A frame whose Doppler is zero on every point, given the IMU around it: nothing when the IMU
/// shows rest (a quantized Doppler reads exactly zero then), otherwise what is wrong.
std::optional<std::string> zeroDopplerProblem(const std::vector<ImuSample>& imu,
                                              const RestParams& p);

}  // namespace freeinit::input
