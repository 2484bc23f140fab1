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
  std::uint64_t seed = 1;
  double duration = 0;             ///< [s] 0: the preset's
  int points_per_frame = 0;        ///< 0: the preset's
  std::string output = "dyna_01.rawlog";  ///< rawlog path; truth files go beside it
  std::string imu_label = "IMU";
  std::string lidar_label = "LIDAR";
  bool accel_in_g = false;         ///< write accelerations in g (to exercise the unit check)
};

class SimApp {
 public:
  SimAppParams params;
  /// Throws on any error; every output is written atomically.
  void run(std::ostream& log);
  std::size_t records_written = 0;
};

}  // namespace freeinit::mrpt_glue
