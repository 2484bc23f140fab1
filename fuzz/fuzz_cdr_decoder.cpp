// Fuzz harness: one CDR payload through the ROS 2 message decoders (ros2/message_decoding.h).
// Byte 0 selects the type (mod 3: 0 sensor_msgs/msg/Imu, 1 sensor_msgs/msg/PointCloud2,
// 2 tf2_msgs/msg/TFMessage); the rest is the payload with its 4-byte encapsulation header.
// Invariants: what decodes is no larger than the payload (cloud data, fields, transforms, strings).
#include <freeinit/ros2/message_decoding.h>

#include "harness.h"

namespace freeinit::fuzz {

std::string fuzzOne(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return "error: empty input";
  const int type = data[0] % 3;
  const std::uint8_t* payload = data + 1;
  const std::size_t n = size - 1;
  try {
    if (type == 0) {
      const ros2::Imu m = ros2::decodeImu(payload, n);
      if (m.header.frame_id.size() > n) broken("a frame id longer than the message");
      return "ok: Imu, frame '" + m.header.frame_id + "'";
    }
    if (type == 1) {
      const ros2::PointCloud2 m = ros2::decodePointCloud2(payload, n);
      std::size_t names = 0;
      for (const ros2::PointField& f : m.fields) names += f.name.size();
      if (m.data.size() > n || m.fields.size() > n / 13 || names > n)
        broken("a decoded cloud larger than its message");
      return "ok: PointCloud2, " + std::to_string(m.fields.size()) + " fields, " +
             std::to_string(m.data.size()) + " bytes of data";
    }
    const ros2::TFMessage m = ros2::decodeTFMessage(payload, n);
    if (m.transforms.size() > n / 72) broken("more transforms than the message holds");
    return "ok: TFMessage, " + std::to_string(m.transforms.size()) + " transforms";
  } catch (const ros2::CdrError& e) {
    return "error: " + firstLine(e.what());
  }
}

}  // namespace freeinit::fuzz
