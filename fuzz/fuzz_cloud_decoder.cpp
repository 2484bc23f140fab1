// Fuzz harness: one serialized sensor_msgs/PointCloud2 through the importer's message check and
// cloud decoder. Byte 0 selects the layout (bits 0-1) and whether invalid points are dropped (bit
// 7 clear) or an error (bit 7 set); the rest is the serialized message, as a bag stores it
// (bytes after its end are ignored).
// Layouts: 0 the release's (float32 x y z intensity velocity, int32 ns time, uint8 line);
// 1 float32 seconds time "t", no line; 2 every field float64, time "t" in seconds, no line;
// 3 a radar's (no time field: spread over 18.5 ms; no line).
// Invariants: decoded points finite when dropping, sorted by time, no more than width x height.
#include <freeinit/ros1/bag_guard.h>
#include <freeinit/ros1/cloud_codec.h>
#include <ros/serialization.h>
#include <sensor_msgs/PointCloud2.h>

#include <cmath>

#include "harness.h"

namespace freeinit::fuzz {
namespace {

ros1::CloudLayout layout(int which) {
  ros1::CloudLayout l;  // 0: the release's
  using ros1::FieldType;
  if (which == 1) {
    l.time.field = {"t", FieldType::kFloat32};
    l.time.scale = 1;
    l.line.name.clear();
  } else if (which == 2) {
    for (ros1::FieldSpec* f : {&l.x, &l.y, &l.z, &l.doppler, &l.intensity})
      f->type = FieldType::kFloat64;
    l.time.field = {"t", FieldType::kFloat64};
    l.time.scale = 1;
    l.line.name.clear();
  } else if (which == 3) {
    l.time.field.name.clear();
    l.time.frame_duration = 0.0185;
    l.line.name.clear();
  }
  return l;
}

}  // namespace

std::string fuzzOne(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return "error: empty input";
  const int which = data[0] & 3;
  const bool drop = (data[0] & 0x80) == 0;
  sensor_msgs::PointCloud2 msg;
  try {
    // Bytes after the message are ignored, as roscpp does (a bag's records must end with it).
    const std::size_t n =
        ros1::checkSerialized(ros1::RosMessage::kPointCloud2, data + 1, size - 1, false);
    // The checked bytes; roscpp's stream wants a mutable pointer but only reads.
    ros::serialization::IStream in(const_cast<std::uint8_t*>(data + 1),
                                   static_cast<std::uint32_t>(n));
    ros::serialization::deserialize(in, msg);
  } catch (const std::exception& e) {
    return "error: " + firstLine(e.what());
  }
  try {
    ros1::DecodeStats stats;
    const LidarFrame f = ros1::decodeCloud(msg, layout(which), drop, &stats);
    const std::uint64_t n = std::uint64_t{msg.width} * msg.height;
    if (f.points.size() + stats.invalid_points != n) broken("points + dropped != width x height");
    for (std::size_t i = 0; i < f.points.size(); ++i) {
      const DopplerPoint& p = f.points[i];
      if (!p.p_l.allFinite() || !std::isfinite(p.doppler) || !std::isfinite(p.time_offset))
        broken("non-finite point decoded");
      if (i > 0 && p.time_offset < f.points[i - 1].time_offset) broken("points not sorted");
    }
    return "ok: layout " + std::to_string(which) + ", " + std::to_string(f.points.size()) +
           " points, " + std::to_string(stats.invalid_points) + " dropped";
  } catch (const ros1::LayoutError& e) {
    return "error: layout " + std::to_string(which) + ": " + firstLine(e.what());
  }
}

}  // namespace freeinit::fuzz
