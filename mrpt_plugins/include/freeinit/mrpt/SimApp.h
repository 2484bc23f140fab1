// freeinit-sim: writes a simulated recording as an MRPT rawlog of CObservationIMU +
// CObservationPointCloud (with a CPointsMapDoppler) plus its ground truth beside it:
//   <out>.rawlog, <out>.truth.csv (ground_truth.h), <out>.truth_tum.txt, <out>.extrinsics.ini
#pragma once

#include <cstdint>
#include <iosfwd>
#include <string>

namespace freeinit::mrpt_glue {

struct SimAppParams {
  std::string preset = "dyna_01";  ///< a freeinit::sim preset name
  /// Optional INI file with a [scenario] section: `preset` (the base, default the one above) and
  /// any ScenarioConfig field (seed, t0, duration, points_per_frame, lines, frame_rate, hfov_deg,
  /// vfov_deg, min_range, max_range, range_sigma, doppler_sigma, outlier_ratio, imu_rate,
  /// gyro_sigma, accel_sigma, random_biases, b_g, b_a). Giving b_g or b_a turns random_biases off
  /// unless it is set. `duration` and `points_per_frame` below override the file when non-zero;
  /// `seed` and `preset` are the defaults of the file's keys.
  std::string scenario_file;
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
  std::size_t records_written = 0;
};

}  // namespace freeinit::mrpt_glue
