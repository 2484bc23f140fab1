// The whole configuration of the Free-Init MRPT application, loaded from an INI file: the core's
// sections (FreeInitConfig) plus [input], [extrinsics] and [output] (result_files.h).
// Every section is declared once (freeinit/io/config_section.h); the file is read by the project's
// strict parser (freeinit/io/ini_file.h), not by MRPT's.
#pragma once

#include <freeinit/app_support/result_files.h>
#include <freeinit/config.h>

#include <iosfwd>
#include <string>
#include <vector>

namespace freeinit::app_support {

/// How observations are picked from the rawlog. INI section [input].
struct InputParams {
  std::string imu_label = "IMU";      ///< sensorLabel of the CObservationIMU to use ("" = any)
  std::string lidar_label = "LIDAR";  ///< sensorLabel of the CObservationPointCloud ("" = any)
  bool imu_accel_in_g = false;        ///< accelerations are in g: multiply by 9.81
  double min_imu_rate = 50.0;         ///< [Hz] slower IMU streams are rejected
  bool drop_invalid_points = false;   ///< drop NaN/inf points (reported) instead of failing
  /// [m/s] the sensor's Doppler bin (0: continuous). With bins, a cloud reads zero on every
  /// point whenever no return's range rate exceeds half a bin, at rest and moving slowly alike;
  /// continuous Doppler is exactly zero everywhere only at rest (checked against the IMU)
  double doppler_resolution = 0;
  /// [MB] most one rawlog record may allocate while it is read (read_budget.h): a record
  /// claiming more (a corrupt length or count) is refused before the allocation
  double max_record_mb = 256;
};

/// Where the LiDAR-IMU extrinsics come from. INI section [extrinsics] (with R_bl, p_bl).
struct ExtrinsicsParams {
  /// Take R_bl, p_bl from the observations' sensorPose (the LiDAR pose relative to the IMU
  /// pose, as freeinit-sim and freeinit-import-bag write it), the default; false: from the INI
  /// keys R_bl (or roll_deg, pitch_deg, yaw_deg) and p_bl, which are refused otherwise.
  bool from_sensor_pose = true;
  bool given_in_ini = false;  ///< set by the loader: the INI gave R_bl, roll/pitch/yaw or p_bl
};

struct AppConfig {
  FreeInitConfig core;
  InputParams input;
  ExtrinsicsParams extrinsics;
  OutputParams output;
};

/// The LiDAR pose in the body frame as an [extrinsics] section writes it: R_bl (row-major) or
/// roll_deg, pitch_deg, yaw_deg (R_bl = Rz(yaw) Ry(pitch) Rx(roll), as mrpt::poses::CPose3D),
/// and p_bl. Shared by the app and the bag importer.
struct LidarPoseParams {
  Mat3 R_bl = Mat3::Identity();  ///< [-]
  double roll_deg = 0, pitch_deg = 0, yaw_deg = 0;
  Vec3 p_bl = Vec3::Zero();  ///< [m]
};
/// [extrinsics] as the app reads it: from_sensor_pose, or the pose keys.
struct ExtrinsicsIniParams {
  bool from_sensor_pose = ExtrinsicsParams{}.from_sensor_pose;
  LidarPoseParams pose;
};

/// The sections' declarations.
const config::Section<InputParams>& inputSection();
const config::Section<ExtrinsicsIniParams>& extrinsicsSection();
/// [extrinsics] as the bag importer reads it: the pose keys only (a bag has no sensor poses).
const config::Section<LidarPoseParams>& extrinsicsPoseSection();
/// Every section of the app's INI file, in the order of the echo.
std::vector<const config::SectionBase*> appSections();

/// The extrinsics an [extrinsics] section's pose keys give: R_bl, or the rotation of the angles
/// when one of them is given (`keys` tells which were), and p_bl. Throws config::ConfigError
/// when both R_bl and an angle are given.
Extrinsics extrinsicsOf(const LidarPoseParams& pose, const config::Checker& keys);
/// The first pose key given (R_bl, roll_deg, pitch_deg, yaw_deg, p_bl), or "".
std::string firstPoseKey(const config::Checker& keys);

/// Loads and validates an INI file. Missing keys keep their defaults; unknown sections, unknown
/// and duplicated keys, malformed or out-of-range values throw config::ConfigError (a
/// std::invalid_argument) naming the file, the line, the section and the key. Keys given under
/// their former names are read, with one notice line each in `notices` (on std::cerr when it is
/// null; see FreeInitConfig::load).
AppConfig loadAppConfig(const std::string& ini_file, std::vector<std::string>* notices = nullptr);
AppConfig loadAppConfig(const config::IniFile& ini, std::vector<std::string>* notices = nullptr);
/// Same from INI text (tests); `source` names it in messages.
AppConfig loadAppConfigFromText(const std::string& ini_text, const std::string& source,
                                std::vector<std::string>* notices = nullptr);
/// Writes the effective configuration as a documented INI (units in comments) that loads back.
void dumpAppConfig(const AppConfig& config, std::ostream& out);

}  // namespace freeinit::app_support
