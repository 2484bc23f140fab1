// `freeinit-icp-slam`: MRPT's icp-slam mapping (CMetricMapBuilderICP, configured by the same INI
// sections as the stock icp-slam app: [MappingApplication], [ICP], ...) on a Doppler LiDAR + IMU
// rawlog, started three ways (IcpSeedMode): plain, seeded by Free-Init's static map, pose and
// velocity, and seeded plus fed with Doppler-inertial odometry. Writes what icp-slam writes (the
// final .simplemap, the path log) per mode, errors against the ground truth beside the rawlog, a
// PNG of the maps and paths, and optionally the stock-classes rawlogs + INI that the stock
// icp-slam app runs on.
#pragma once

#include <freeinit/app_support/app_config.h>
#include <freeinit/app_support/icp_slam_bridge.h>
#include <freeinit/initial_state.h>

#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

namespace freeinit::apps {

struct IcpSlamAppParams {
  std::string icp_ini;       ///< icp-slam INI ([MappingApplication], [ICP], [freeinit_scan])
  std::string freeinit_ini;  ///< Free-Init INI (ini/freeinit.ini)
  std::string rawlog;        ///< input: Doppler LiDAR + IMU rawlog (freeinit-sim's format)
  std::string out_dir = "icp_slam_out";
  std::vector<app_support::IcpSeedMode> modes = {app_support::IcpSeedMode::Plain,
                                                 app_support::IcpSeedMode::Seeded,
                                                 app_support::IcpSeedMode::Odometry};
  std::string export_dir;      ///< not empty: also write <dir>/<mode>.rawlog + <mode>.ini (stock)
  bool snapshot = true;        ///< trajectories.png
  int snapshot_width = 1400;   ///< [px]
  int snapshot_height = 1050;  ///< [px]
};

/// One icp-slam run.
struct IcpSlamRun {
  app_support::IcpSeedMode mode = app_support::IcpSeedMode::Plain;
  std::vector<app_support::PlanarPathSample> path;  ///< robot pose after each scan
  std::size_t keyframes = 0;        ///< keyframes in the final map (the seed included)
  std::vector<float> map_x, map_y;  ///< final points map
  std::optional<app_support::PathErrors>
      errors;  ///< from the state time on, when the truth is present
};

class IcpSlamApp {
 public:
  IcpSlamAppParams params;

  /// The outputs in out_dir (and export_dir) are one set each (output_set.h): installed when the
  /// run is complete, replacing an earlier run's; a run that throws (bad input or configuration,
  /// a stop request) leaves nothing of its own there and the earlier run's outputs as they were.
  /// Returns 0, or 3 when Free-Init did not initialize and a seeded mode was asked for (the plain
  /// run is still done).
  int run(std::ostream& log);
  /// The command line (`main` of freeinit-icp-slam): parses it, runs, returns the exit code.
  static int main(int argc, char** argv);

  // Filled by run(), for callers and tests.
  InitResult freeinit;
  std::vector<IcpSlamRun> runs;
  /// The Doppler-inertial odometry alone at the same scans (when the odometry mode ran).
  std::optional<app_support::PathErrors> odometry_errors;
};

}  // namespace freeinit::apps
