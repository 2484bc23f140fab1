// Decodes the CDR payloads of the ROS 2 messages the importer reads into the plain structs of
// messages.h. Each throws CdrError naming the field for a message that does not decode (a length
// or count beyond the bytes, a string without its NUL, an unsupported encapsulation), and never
// allocates more than the payload's size (times a small constant for the structs).
// Bytes left over after the last field are allowed (DDS payloads may be padded).
#pragma once

#include <freeinit/ros2/cdr_reader.h>
#include <freeinit/ros2/messages.h>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace freeinit::ros2 {

/// The ROS 2 type names, as recordings store them.
inline constexpr const char* kImuType = "sensor_msgs/msg/Imu";
inline constexpr const char* kPointCloud2Type = "sensor_msgs/msg/PointCloud2";
inline constexpr const char* kTFMessageType = "tf2_msgs/msg/TFMessage";

Imu decodeImu(const std::uint8_t* data, std::size_t size);
PointCloud2 decodePointCloud2(const std::uint8_t* data, std::size_t size);
TFMessage decodeTFMessage(const std::uint8_t* data, std::size_t size);

inline Imu decodeImu(const std::vector<std::uint8_t>& d) { return decodeImu(d.data(), d.size()); }
inline PointCloud2 decodePointCloud2(const std::vector<std::uint8_t>& d) {
  return decodePointCloud2(d.data(), d.size());
}
inline TFMessage decodeTFMessage(const std::vector<std::uint8_t>& d) {
  return decodeTFMessage(d.data(), d.size());
}

}  // namespace freeinit::ros2
