// freeinit-sim: writes a simulated recording as an MRPT rawlog of CObservationIMU +
// CObservationPointCloud (with a CPointsMapDoppler) plus its ground truth beside it:
//   <out>.rawlog            what the estimator reads: the declared extrinsics in each sensorPose,
//                           LiDAR stamps on the LiDAR clock
//   <out>.extrinsics.ini    the declared extrinsics (equal to the truth unless the scenario
//                           declares them wrong on purpose)
//   <out>.truth.csv         (ground_truth.h), <out>.truth_tum.txt: the true body trajectory
//   <out>.truth_extrinsics.ini  the true extrinsics (comment: the true LiDAR clock offset)
//   <out>.scenario.ini      the complete scenario: `freeinit-sim -c` on it gives the same recording
#pragma once

#include <cstdint>
#include <iosfwd>
#include <string>

namespace freeinit::apps {

struct SimAppParams {
  std::string preset = "dyna_01";  ///< a freeinit::sim preset name
  /// Optional INI file with a [scenario] section (freeinit/sim/scenario_ini.h): `preset` (the base:
  /// a preset name or `random`; default the one above), `seed` and any other scenario key, e.g.
  /// "preset = stat_01, seed = 7, duration = 0.5, b_g = ..." or the complete form a run writes to
  /// <out>.scenario.ini. Giving b_g or b_a turns random_biases off unless it is set. `duration` and
  /// `points_per_frame` below override the file when non-zero; `seed` and `preset` are the
  /// defaults of the file's keys.
  std::string scenario_file;
  bool random = false;  ///< simulate freeinit::sim::randomScenario(seed) (not with scenario_file)
  std::uint64_t seed = 1;
  double duration = 0;                    ///< [s] 0: the preset's
  int points_per_frame = 0;               ///< 0: the preset's
  std::string output = "dyna_01.rawlog";  ///< rawlog path; truth files go beside it
  std::string imu_label = "IMU";
  std::string lidar_label = "LIDAR";
  bool accel_in_g = false;  ///< write accelerations in g (to exercise the unit check)
};

class SimApp {
 public:
  SimAppParams params;
  /// Throws on any error; every output is written atomically.
  void run(std::ostream& log);
  /// The command line (`main` of freeinit-sim): parses it, runs, returns the exit code.
  static int main(int argc, char** argv);
  /// The [scenario] keys of a scenario file, one per line with unit, default, range and doc.
  static std::string scenarioKeys();
  std::size_t records_written = 0;
};

}  // namespace freeinit::apps
