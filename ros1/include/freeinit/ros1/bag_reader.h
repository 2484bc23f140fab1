// Streams the IMU and LiDAR messages of a ROS1 bag into core types, in header-time order, without
// loading the bag: a rosbag::View reads chunk by chunk and a small reorder buffer
// (BagImportConfig::reorder_window) puts the messages of both topics in stamp order (IMU first on
// ties, as the simulator writes its rawlogs).
//
// Scan stamps come from the cloud headers, from a trigger topic matched by sequence number (read
// first, in full: one small message per scan), or from the bag's receive time
// (BagImportConfig::stamp_source).
//
// Bad bags never import silently wrong: a missing topic, a topic of another message type, a cloud
// that does not match the configured layout, accelerations in the other unit, an IMU message
// without gyro or accelerometer data, or a message later than the reorder window throw BagError
// naming the file, the topic and the message. Messages whose stamp does not increase within their
// topic, or that are unusable (zero stamp, NaN IMU values, clouds with no valid point, no trigger),
// are skipped and counted in the summary; NaN points are dropped and counted.
//
// Corrupt bags: the file's structure is checked before librosbag opens it (bag_guard.h), each
// message's serialized lengths before roscpp deserializes it, and any exception left (bad_alloc
// included) becomes a BagError naming the file and the message.
#pragma once

#include <freeinit/ros1/bag_import_config.h>
#include <freeinit/types.h>

#include <cstddef>
#include <functional>
#include <iosfwd>
#include <stdexcept>
#include <string>
#include <vector>

namespace freeinit::ros1 {

class BagError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// What was read from one topic. Times are header stamps (LiDAR: plus lidar_time_offset).
struct TopicSummary {
  std::string topic;
  std::string type;
  std::size_t in_bag = 0;        ///< messages on the topic
  std::size_t imported = 0;      ///< messages passed on
  std::size_t out_of_order = 0;  ///< skipped: stamp earlier than the previous one of the topic
  std::size_t duplicated = 0;    ///< skipped: same stamp as the previous one of the topic
  std::size_t unusable = 0;      ///< skipped: zero stamp, NaN values, no valid point
  std::size_t untriggered = 0;  ///< skipped: no trigger of the cloud's seq (stamp_source = trigger)
  double first = 0, last = 0;   ///< [s] first and last imported stamps
  double median_interval = 0;   ///< [s]
  std::size_t gaps = 0;         ///< intervals > gap_factor * median_interval
  double largest_gap = 0;       ///< [s]
  double largest_gap_at = 0;    ///< [s] stamp at the end of the largest gap
  std::size_t skipped() const { return out_of_order + duplicated + unusable + untriggered; }
  double meanRate() const;  ///< [Hz] (imported - 1) / (last - first)
};

/// The trigger topic (stamp_source = trigger).
struct TriggerSummary {
  std::string topic;
  std::size_t in_bag = 0;        ///< std_msgs/Header messages on it
  std::size_t used = 0;          ///< triggers that stamped a cloud
  std::size_t repeated_seq = 0;  ///< triggers whose seq another trigger also has
  /// [s] median of (cloud bag time - trigger stamp) over the matched clouds: the publishing delay
  /// plus the offset between the recorder's clock and the trigger's.
  double median_bag_delay = 0;
};

struct BagSummary {
  std::string file;
  TopicSummary imu, lidar;
  TriggerSummary trigger;                 ///< empty topic: stamps not from a trigger
  std::vector<std::string> other_topics;  ///< "topic (type, N messages)", not imported
  std::size_t points = 0;                 ///< LiDAR points passed on
  std::size_t invalid_points = 0;         ///< NaN/inf points dropped
  double accel_mean_norm = 0;             ///< [m/s^2] over the first unit_check_samples samples
  double gap_factor = 0;                  ///< gaps are intervals > gap_factor * median interval
  /// Prints messages per topic, rates, time span, gaps and skips.
  void print(std::ostream& out) const;
};

struct BagReadCallbacks {
  std::function<void(const ImuSample&)> imu;
  std::function<void(LidarFrame&&)> frame;
  std::function<void(std::size_t, std::size_t)> progress;  ///< (messages done, total); optional
};

/// Reads `path` and calls the callbacks in stamp order. Throws BagError (see above) or
/// std::invalid_argument for an invalid configuration.
BagSummary readBag(const std::string& path, const BagImportConfig& config,
                   const BagReadCallbacks& callbacks);

}  // namespace freeinit::ros1
