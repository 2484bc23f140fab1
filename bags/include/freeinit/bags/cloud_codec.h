// PointCloud2 <-> freeinit::LidarFrame with a configurable field layout, for ROS 1 and ROS 2 alike:
// both generations' sensor_msgs/PointCloud2 carry the same header stamp, height, width, fields
// {name, offset, datatype, count}, is_bigendian, point_step, row_step and data, which a
// PointCloudView points at without copying the data (view() below for ROS 2; ros1/cloud_codec.h
// for roscpp's message).
// Decoding checks the layout against the message (fields present, declared datatypes, sizes within
// point_step and the buffer), reads either byte order, and drops NaN/inf points when allowed.
#pragma once

#include <freeinit/bags/import_config.h>
#include <freeinit/ros2/messages.h>
#include <freeinit/types.h>

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <vector>

namespace freeinit::bags {

/// A message that does not match the configured layout; the message says what and how to fix it.
class LayoutError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// What decoding one cloud dropped.
struct DecodeStats {
  std::size_t invalid_points = 0;  ///< NaN/inf coordinates, Doppler or time (dropped)
};

/// What decodeCloud reads of a PointCloud2; `fields` and `data` are not owned.
struct PointCloudView {
  std::int64_t stamp_sec = 0;       ///< [s] header stamp (ROS 1 uint32, ROS 2 int32)
  std::uint32_t stamp_nanosec = 0;  ///< [ns] within the second
  std::uint32_t height = 0, width = 0;
  std::uint32_t point_step = 0, row_step = 0;  ///< [bytes]
  bool is_bigendian = false;
  const std::vector<ros2::PointField>* fields = nullptr;
  const std::uint8_t* data = nullptr;
  std::size_t size = 0;  ///< [bytes] of data
  /// [s] the header stamp as both ROS generations compute it (sec + 1e-9 nanosec).
  double stamp() const {
    return static_cast<double>(stamp_sec) + 1e-9 * static_cast<double>(stamp_nanosec);
  }
  bool stampIsZero() const { return stamp_sec == 0 && stamp_nanosec == 0; }
};

/// The view of a ROS 2 cloud (valid while `msg` is).
PointCloudView view(const ros2::PointCloud2& msg);

/// The frame of one cloud: stamp = header stamp (the reader adds the LiDAR-IMU offset); points
/// sorted by time offset (stable). Throws LayoutError on a layout mismatch, or on an invalid point
/// when !drop_invalid.
LidarFrame decodeCloud(const PointCloudView& cloud, const CloudLayout& layout, bool drop_invalid,
                       DecodeStats* stats = nullptr);

/// Encodes a frame with `layout` (an unorganized cloud, height 1, is_dense when every value is
/// finite, header.frame_id "aeva"). `reflectivity` adds a float32 "reflectivity" field of zeros,
/// as the Aeva driver has one. Fields are packed in the order x y z intensity reflectivity doppler
/// time line. `big_endian` writes every value big-endian (and sets is_bigendian). Used by tests and
/// tools that write recordings.
void encodeCloud(const LidarFrame& frame, const CloudLayout& layout, bool reflectivity,
                 bool big_endian, ros2::PointCloud2& msg);

}  // namespace freeinit::bags
