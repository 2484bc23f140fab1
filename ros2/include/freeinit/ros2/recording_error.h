// The one exception type of the ROS 2 readers: a recording that cannot be read as asked. Its
// message is one line naming the file (or folder) and what is wrong, e.g.
//   "x.mcap: an MCAP file (ROS 2): chunk 12 compressed with 'bz2', which is not supported"
//   "run1: a rosbag2 folder without metadata.yaml"
//   "x.db3: topic /foo not found; the recording has: /imu (sensor_msgs/msg/Imu), ..."
// CDR decoding errors (cdr_reader.h) name the field instead of a file: the caller knows the
// message.
#pragma once

#include <stdexcept>

namespace freeinit::ros2 {

class RecordingError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace freeinit::ros2
