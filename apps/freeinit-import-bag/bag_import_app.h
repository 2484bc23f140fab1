// freeinit-import-bag: a ROS1 bag (the Free-Init / FMCW-LIO release layout by default) to a typed
// rawlog that the freeinit app reads, written with the simulator's writer (RawlogWriter):
//   <out>.rawlog            CObservationIMU + CObservationPointCloud (CPointsMapDoppler), in stamp
//                           order, each cloud's sensorPose = the extrinsics
//   <out>.extrinsics.ini    [extrinsics] R_bl, p_bl, as freeinit-sim writes it
//   --doppler-fit-csv FILE  optional: each imported scan's sensor velocity from its Doppler alone
//                           (ros1/doppler_fit.h), a no-IMU reference
// The configuration is an INI file: [bag_import] (topics, PointCloud2 fields and types, units,
// scan stamp source, clock offset, Doppler mode; see ini/import_bag.ini), [extrinsics] (R_bl or
// roll/pitch/yaw_deg, and p_bl, read by the main app's loader) and optionally [doppler_fit]. Each
// output is written atomically; a bad bag or configuration fails before any exists.
#pragma once

#include <freeinit/ros1/bag_import_config.h>
#include <freeinit/ros1/bag_reader.h>
#include <freeinit/ros1/doppler_fit.h>

#include <iosfwd>
#include <string>

namespace freeinit::config {
template <class S>
class Section;
}  // namespace freeinit::config

namespace freeinit::apps {

struct BagImportAppParams {
  std::string bag;
  std::string config_file;  ///< INI with [bag_import] and [extrinsics]
  std::string output;       ///< rawlog path ("" = the bag's path with .rawlog)
  /// CSV of the per-scan Doppler-only velocity fits ("" = none): stamp, t, points, inliers, ok,
  /// v_x v_y v_z [m/s, sensor frame], their sigmas and covariances, residual_sigma.
  std::string doppler_fit_csv;
  bool progress = true;
  bool progress_terminal = false;
};

/// The importer's whole configuration, from its INI file.
struct BagImportSettings {
  ros1::BagImportConfig bag;
  Extrinsics extrinsics;
  std::string imu_label = "IMU";      ///< sensorLabel written on the IMU observations
  std::string lidar_label = "LIDAR";  ///< sensorLabel written on the point clouds
  /// The freeinit configuration made for this sensor, relative to the import INI's folder,
  /// suggested after the import ("": the defaults suit it).
  std::string freeinit_config;
  ros1::DopplerFitParams doppler_fit;  ///< [doppler_fit]: the per-scan fits of --doppler-fit-csv
};

/// The header line of the --doppler-fit-csv file.
extern const char* const kDopplerFitCsvHeader;

/// Loads and validates; unknown sections and keys, duplicated keys, malformed or out-of-range
/// values and missing extrinsics throw config::ConfigError (a std::invalid_argument) naming the
/// file, the line, the section and the key.
BagImportSettings loadBagImportSettings(const std::string& ini_file);
/// The declaration of [bag_import] (its [extrinsics] is extrinsicsPoseSection(), app_config.h).
const config::Section<BagImportSettings>& bagImportSection();
/// The declaration of [doppler_fit] (optional; read for --doppler-fit-csv).
const config::Section<ros1::DopplerFitParams>& dopplerFitSection();

class BagImportApp {
 public:
  BagImportAppParams params;
  /// Throws on any error (nothing is written then). Returns the exit code (0).
  int run(std::ostream& log);
  /// The command line (`main` of freeinit-import-bag): parses it, runs, returns the exit code.
  static int main(int argc, char** argv);

  BagImportSettings settings;  ///< filled by run()
  ros1::BagSummary summary;    ///< filled by run()
  std::string rawlog_written;  ///< filled by run()
};

}  // namespace freeinit::apps
