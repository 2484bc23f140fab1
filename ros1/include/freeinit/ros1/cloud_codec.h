// roscpp's sensor_msgs/PointCloud2 <-> freeinit::LidarFrame through the codec both ROS generations
// share (bags/cloud_codec.h): the roscpp message is viewed (its data is not copied) or filled from
// the neutral message.
#pragma once

#include <freeinit/bags/cloud_codec.h>
#include <freeinit/ros1/bag_import_config.h>
#include <freeinit/types.h>

#include <vector>

namespace sensor_msgs {
template <class Allocator>
struct PointCloud2_;
using PointCloud2 = PointCloud2_<std::allocator<void>>;
}  // namespace sensor_msgs

namespace freeinit::ros1 {

using bags::DecodeStats;
using bags::LayoutError;

/// The view of a roscpp cloud: its field list converted into `fields` (a few entries), its data
/// pointed at. Valid while `msg` and `fields` are.
bags::PointCloudView view(const sensor_msgs::PointCloud2& msg,
                          std::vector<ros2::PointField>& fields);

/// bags::decodeCloud of the roscpp message.
LidarFrame decodeCloud(const sensor_msgs::PointCloud2& msg, const CloudLayout& layout,
                       bool drop_invalid, DecodeStats* stats = nullptr);

/// bags::encodeCloud into the roscpp message.
void encodeCloud(const LidarFrame& frame, const CloudLayout& layout, bool reflectivity,
                 bool big_endian, sensor_msgs::PointCloud2& msg);

}  // namespace freeinit::ros1
