// The whole configuration of the Free-Init MRPT application, loaded from an MRPT-style INI file:
// one [section] per core config struct plus [input], [extrinsics] and [output].
#pragma once

#include <freeinit/config.h>

#include <iosfwd>
#include <string>

namespace freeinit::mrpt_glue {

/// How observations are picked from the rawlog. INI section [input].
struct InputParams {
  std::string imu_label = "IMU";      ///< sensorLabel of the CObservationIMU to use ("" = any)
  std::string lidar_label = "LIDAR";  ///< sensorLabel of the CObservationPointCloud ("" = any)
  bool imu_accel_in_g = false;        ///< accelerations are in g: multiply by 9.81
  double min_imu_rate = 50.0;         ///< [Hz] slower IMU streams are rejected
  bool drop_invalid_points = false;   ///< drop NaN/inf points (reported) instead of failing
};

/// Where the LiDAR-IMU extrinsics come from. INI section [extrinsics] (with R_bl, p_bl).
struct ExtrinsicsParams {
  /// Take R_bl, p_bl from the observations' sensorPose (LiDAR pose relative to the IMU pose)
  /// instead of the INI keys.
  bool from_sensor_pose = false;
  bool given_in_ini = false;  ///< set by the loader: the INI gave R_bl or roll/pitch/yaw
};

/// What the app writes to its output folder. INI section [output].
struct OutputParams {
  bool simplemap = true;      ///< static_map.simplemap (stock MRPT classes only)
  bool ply = true;            ///< static_map.ply
  bool trajectory = true;     ///< trajectory_tum.txt
  bool velocities = true;     ///< velocimeter.csv
  bool snapshots = true;      ///< PNGs rendered offscreen
  int snapshot_width = 1280;  ///< [px]
  int snapshot_height = 800;  ///< [px]
};

struct AppConfig {
  FreeInitConfig core;
  InputParams input;
  ExtrinsicsParams extrinsics;
  OutputParams output;
};

/// Loads and validates an INI file. Missing keys keep their defaults; unknown keys in known
/// sections, malformed or out-of-range values throw std::invalid_argument naming file and key.
AppConfig loadAppConfig(const std::string& ini_file);
/// Same from INI text (tests); `source` names it in messages.
AppConfig loadAppConfigFromText(const std::string& ini_text, const std::string& source);
/// Writes the effective configuration as a documented INI (units in comments) that loads back.
void dumpAppConfig(const AppConfig& config, std::ostream& out);

}  // namespace freeinit::mrpt_glue
