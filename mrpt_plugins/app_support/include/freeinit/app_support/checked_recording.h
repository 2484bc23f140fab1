// A whole recording in core types, read and checked by the ingest path (ingest.h): for the tools
// that use every sample (evaluation against baselines, icp-slam, playing a rawlog as a stream).
// Free-Init itself reads only what its window needs (FreeInitApp).
#pragma once

#include <freeinit/app_support/app_config.h>
#include <freeinit/mrpt_plugins/rawlog_reader.h>
#include <freeinit/types.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace freeinit::app_support {

/// The recording in core types, as the estimator will see it.
struct CheckedRecording {
  std::vector<ImuSample> imu;
  std::vector<LidarFrame> frames;
  /// [ns] exact stamps of `imu` and `frames` (MRPT's 100 ns clock); empty if one is outside the
  /// range the live stream carries (before 1970).
  std::vector<std::int64_t> imu_stamp_ns, frame_stamp_ns;
  std::optional<Extrinsics> sensor_pose_extrinsics;  ///< LiDAR sensorPose relative to the IMU's
  std::size_t invalid_points_dropped = 0;
  std::vector<std::string> warnings;
};

/// Reads the whole rawlog through the ingest path. Throws InputError naming the file and the
/// record for: a file that cannot be read to its end (truncated, corrupt, unregistered class),
/// any record failing the record checks (IMU without gyro/accel fields or not finite, clouds
/// without Doppler (any class but CPointsMapDoppler), empty, with NaN/inf points unless [input]
/// drop_invalid_points, timestamps going backwards or duplicated, Doppler zero everywhere while
/// the IMU moves), no IMU or no LiDAR observations with the configured labels, an IMU slower than
/// [input] min_imu_rate, accelerations in g without [input] imu_accel_in_g (or the reverse), a
/// recording shorter than the window.
CheckedRecording readRecording(const std::string& path, const AppConfig& config,
                               const mrpt_plugins::RawlogIndexPolicy& index = {});

}  // namespace freeinit::app_support
