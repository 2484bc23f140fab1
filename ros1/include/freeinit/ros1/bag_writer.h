// Writes IMU samples and LiDAR frames as a ROS1 bag laid out as `BagWriteOptions::config` reads
// it (topics, PointCloud2 fields and types, IMU unit, LiDAR time offset): the inverse of
// readBag. Used by the tests to make bags from simulator recordings, and by tools that export.
#pragma once

#include <freeinit/ros1/bag_import_config.h>
#include <freeinit/ros2/messages.h>
#include <freeinit/types.h>

#include <cstdint>
#include <string>
#include <vector>

namespace freeinit::ros1 {

struct BagWriteOptions {
  BagImportConfig config;
  /// [s] bag (receive) time of a cloud after its header stamp, as a driver that publishes a frame
  /// once swept; IMU messages are recorded at their stamps.
  double lidar_publish_delay = 0.1;
  bool big_endian = false;   ///< PointCloud2 data big-endian (is_bigendian = true)
  bool reflectivity = true;  ///< add the Aeva driver's float32 reflectivity field (zeros)
  enum class Compression { kNone, kBz2, kLz4 } compression = Compression::kNone;  ///< chunks
  /// [bytes] a chunk is closed once it holds this much (rosbag record's default: 768 KB).
  std::uint32_t chunk_threshold = 768 * 1024;
  std::string imu_frame_id = "imu";     ///< header.frame_id of the IMU messages
  std::string lidar_frame_id = "aeva";  ///< header.frame_id of the clouds
  /// Written as one tf2_msgs/TFMessage on config.tf_static_topic at the first IMU stamp (none
  /// when empty).
  std::vector<ros2::TransformStamped> tf_static;
};

/// Writes `path` through a temporary file renamed when complete. Throws std::runtime_error.
void writeBag(const std::string& path, const std::vector<ImuSample>& imu,
              const std::vector<LidarFrame>& frames, const BagWriteOptions& options);

}  // namespace freeinit::ros1
