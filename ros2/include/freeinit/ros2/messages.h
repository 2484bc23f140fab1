// The ROS 2 messages the importer reads, as plain structs with no ROS type: what
// message_decoding.h decodes from CDR. Field names and units are those of the ROS 2 definitions
// (sensor_msgs/msg/PointCloud2, sensor_msgs/msg/Imu, tf2_msgs/msg/TFMessage).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace freeinit::ros2 {

/// builtin_interfaces/msg/Time.
struct Time {
  std::int32_t sec = 0;       ///< [s] UNIX
  std::uint32_t nanosec = 0;  ///< [ns] within the second
  std::int64_t nanoseconds() const { return std::int64_t{sec} * 1000000000 + nanosec; }
  double seconds() const { return sec + 1e-9 * nanosec; }
};

/// std_msgs/msg/Header (ROS 2: no sequence number).
struct Header {
  Time stamp;
  std::string frame_id;
};

struct Vector3 {
  double x = 0, y = 0, z = 0;
};

/// geometry_msgs/msg/Quaternion; ROS order x, y, z, w.
struct Quaternion {
  double x = 0, y = 0, z = 0, w = 1;
};

/// sensor_msgs/msg/PointField. datatype: 1 int8, 2 uint8, 3 int16, 4 uint16, 5 int32, 6 uint32,
/// 7 float32, 8 float64.
struct PointField {
  std::string name;
  std::uint32_t offset = 0;  ///< [bytes] within a point
  std::uint8_t datatype = 0;
  std::uint32_t count = 0;  ///< elements of the field
};

/// sensor_msgs/msg/PointCloud2: `data` holds height rows of row_step bytes, each of width points
/// of point_step bytes, in the byte order is_bigendian says. Decoding checks the message's
/// structure, not that the layout fits the data (the cloud codec does, against its layout).
struct PointCloud2 {
  Header header;
  std::uint32_t height = 0;
  std::uint32_t width = 0;
  std::vector<PointField> fields;
  bool is_bigendian = false;
  std::uint32_t point_step = 0;  ///< [bytes]
  std::uint32_t row_step = 0;    ///< [bytes]
  std::vector<std::uint8_t> data;
  bool is_dense = false;
};

/// sensor_msgs/msg/Imu. A covariance whose element 0 is -1 means the quantity is not provided.
struct Imu {
  Header header;
  Quaternion orientation;
  std::array<double, 9> orientation_covariance{};  ///< [rad^2] row-major, about x, y, z
  Vector3 angular_velocity;                        ///< [rad/s]
  std::array<double, 9> angular_velocity_covariance{};
  Vector3 linear_acceleration;  ///< [m/s^2]
  std::array<double, 9> linear_acceleration_covariance{};
};

/// geometry_msgs/msg/TransformStamped: the pose of child_frame_id in header.frame_id, i.e.
/// p_parent = rotation * p_child + translation.
struct TransformStamped {
  Header header;
  std::string child_frame_id;
  Vector3 translation;  ///< [m]
  Quaternion rotation;
};

/// tf2_msgs/msg/TFMessage (on /tf and /tf_static).
struct TFMessage {
  std::vector<TransformStamped> transforms;
};

}  // namespace freeinit::ros2
