// sensor_msgs/PointCloud2 <-> freeinit::LidarFrame with a configurable field layout.
// Decoding checks the layout against the message (fields present, declared datatypes, sizes within
// point_step and the buffer), reads either byte order, and drops NaN/inf points when allowed.
#pragma once

#include <freeinit/ros1/bag_import_config.h>
#include <freeinit/types.h>

#include <cstddef>
#include <stdexcept>

namespace sensor_msgs {
template <class Allocator>
struct PointCloud2_;
using PointCloud2 = PointCloud2_<std::allocator<void>>;
}  // namespace sensor_msgs

namespace freeinit::ros1 {

/// A message that does not match the configured layout; the message says what and how to fix it.
class LayoutError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// What decoding one cloud dropped.
struct DecodeStats {
  std::size_t invalid_points = 0;  ///< NaN/inf coordinates, Doppler or time (dropped)
};

/// The frame of one cloud: stamp = header stamp + layout time offset is NOT applied here (the
/// reader adds the LiDAR-IMU offset); points sorted by time offset (stable).
/// Throws LayoutError on a layout mismatch, or on an invalid point when !drop_invalid.
LidarFrame decodeCloud(const sensor_msgs::PointCloud2& msg, const CloudLayout& layout,
                       bool drop_invalid, DecodeStats* stats = nullptr);

/// Encodes a frame with `layout` (an unorganized cloud, height 1, is_dense when every value is
/// finite). `reflectivity` adds a float32 "reflectivity" field of zeros, as the Aeva driver has
/// one. Fields are packed in the order x y z intensity reflectivity doppler time line. `big_endian`
/// writes every value big-endian (and sets is_bigendian). Used by tests and tools that write bags.
void encodeCloud(const LidarFrame& frame, const CloudLayout& layout, bool reflectivity,
                 bool big_endian, sensor_msgs::PointCloud2& msg);

}  // namespace freeinit::ros1
