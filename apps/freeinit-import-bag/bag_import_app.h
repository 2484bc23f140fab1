// freeinit-import-bag: a ROS recording (the Free-Init / FMCW-LIO release layout by default) to a
// typed rawlog that the freeinit app reads, written with the simulator's writer (RawlogWriter). The
// input is recognised by its content: a ROS 1 bag (ros1/bag_reader.h), an MCAP file, a rosbag2
// folder or a single rosbag2 .db3 (bags/ros2_import.h); the same settings read both generations.
//   <out>.rawlog            CObservationIMU + CObservationPointCloud (CPointsMapDoppler), in stamp
//                           order, each cloud's sensorPose = the extrinsics
//   <out>.extrinsics.ini    [extrinsics] R_bl, p_bl, as freeinit-sim writes it
//   --doppler-fit-csv FILE  optional: each imported scan's sensor velocity from its Doppler alone
//                           (ros1/doppler_fit.h), a no-IMU reference
// The configuration is an INI file: [bag_import] (topics, PointCloud2 fields and types, units,
// scan stamp source, clock offset, Doppler mode; see ini/import_bag.ini), [extrinsics] (R_bl or
// roll/pitch/yaw_deg, and p_bl, read by the main app's loader) and optionally [doppler_fit].
// Extrinsics: the INI's when it gives them, else those of the recording's /tf_static (from the
// IMU's frame_id to the LiDAR's); when both exist and differ by more than 0.1 deg or 1 mm, a
// warning says so (the INI's are used). Each output is written atomically; a bad recording or
// configuration fails before any exists.
#pragma once

#include <freeinit/bags/import_section.h>
#include <freeinit/bags/static_transforms.h>
#include <freeinit/ros1/bag_import_config.h>
#include <freeinit/ros1/bag_reader.h>
#include <freeinit/ros1/doppler_fit.h>

#include <iosfwd>
#include <optional>
#include <string>

namespace freeinit::config {
template <class S>
class Section;
}  // namespace freeinit::config

namespace freeinit::apps {

struct BagImportAppParams {
  std::string bag;          ///< a ROS 1 bag, an MCAP file, a rosbag2 folder or .db3
  std::string config_file;  ///< INI with [bag_import] and [extrinsics]
  std::string output;       ///< rawlog path ("" = the bag's path with .rawlog)
  /// CSV of the per-scan Doppler-only velocity fits ("" = none): stamp, t, points, inliers, ok,
  /// v_x v_y v_z [m/s, sensor frame], their sigmas and covariances, residual_sigma.
  std::string doppler_fit_csv;
  bool progress = true;
  bool progress_terminal = false;
};

/// The importer's whole configuration, from its INI file.
/// [bag_import] (bags::ImportSettings: the topics, layout and labels) and the rest.
struct BagImportSettings : bags::ImportSettings {
  Extrinsics extrinsics;               ///< after run(): the extrinsics used
  bool extrinsics_given = false;       ///< [extrinsics] gives them
  std::string extrinsics_source;       ///< after run(): where the extrinsics used come from
  ros1::DopplerFitParams doppler_fit;  ///< [doppler_fit]: the per-scan fits of --doppler-fit-csv
};

/// The header line of the --doppler-fit-csv file.
extern const char* const kDopplerFitCsvHeader;

/// Loads and validates; unknown sections and keys, duplicated keys, malformed or out-of-range
/// values and missing extrinsics throw config::ConfigError (a std::invalid_argument) naming the
/// file, the line, the section and the key.
BagImportSettings loadBagImportSettings(const std::string& ini_file);
/// The declaration of [doppler_fit] (optional; read for --doppler-fit-csv).
const config::Section<ros1::DopplerFitParams>& dopplerFitSection();

class BagImportApp {
 public:
  BagImportAppParams params;
  /// Throws on any error (nothing is written then). Returns the exit code (0).
  int run(std::ostream& log);
  /// The command line (`main` of freeinit-import-bag): parses it, runs, returns the exit code.
  static int main(int argc, char** argv);

 private:
  /// settings.extrinsics and extrinsics_source from the INI or the recording (see above); throws
  /// std::invalid_argument when neither gives them.
  void chooseExtrinsics();

 public:
  BagImportSettings settings;  ///< filled by run()
  ros1::BagSummary summary;    ///< filled by run()
  std::string rawlog_written;  ///< filled by run()
  /// Filled by run(): the extrinsics of the recording's /tf_static, when it links the frames.
  std::optional<bags::RecordedExtrinsics> recorded_extrinsics;
  /// Filled by run(): "" or the warning that the INI's and the recording's extrinsics differ.
  std::string extrinsics_warning;
};

/// The rawlog freeinit-import-bag writes for `input` by default: the input's path without its
/// extension (.bag, .mcap, .db3; a folder: its name) + ".rawlog".
std::string defaultRawlogName(const std::string& input);

}  // namespace freeinit::apps
