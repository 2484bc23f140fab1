// What the importers of both ROS generations share once a message is decoded: the reorder buffer
// that puts the IMU samples and LiDAR frames in header-time order (BagImportConfig::
// reorder_window; IMU first on ties, as the simulator writes its rawlogs), the per-topic checks
// (stamps that do not increase, unusable messages, rates and gaps), the accelerometer unit check
// and the summary. A container reader (ros1/bag_reader.h, ros2_import.h) opens the recording,
// checks its topics, decodes each message and feeds it here.
//
// No ROS and no MRPT type appears here.
#pragma once

#include <freeinit/bags/import_config.h>
#include <freeinit/types.h>

#include <cstddef>
#include <functional>
#include <iosfwd>
#include <map>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

namespace freeinit::bags {

/// A recording that cannot be imported: one line naming the file (and the topic and message).
class BagError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// What was read from one topic. Times are header stamps (LiDAR: plus lidar_time_offset).
struct TopicSummary {
  std::string topic;
  std::string type;
  std::size_t in_bag = 0;        ///< messages on the topic (read, where the recording has no count)
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

/// The trigger topic (stamp_source = trigger, ROS 1).
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
  std::string kind;  ///< "a ROS 1 bag", "an MCAP file (ROS 2)", ...
  TopicSummary imu, lidar;
  TriggerSummary trigger;                 ///< empty topic: stamps not from a trigger
  std::vector<std::string> other_topics;  ///< "topic (type, N messages)", not imported
  std::size_t points = 0;                 ///< LiDAR points passed on
  std::size_t invalid_points = 0;         ///< NaN/inf points dropped
  double accel_mean_norm = 0;             ///< [m/s^2] over the first unit_check_samples samples
  double gap_factor = 0;                  ///< gaps are intervals > gap_factor * median interval
  std::vector<std::string> warnings;      ///< the container reader's (e.g. a cut MCAP file)
  /// Prints messages per topic, rates, time span, gaps and skips.
  void print(std::ostream& out) const;
};

struct BagReadCallbacks {
  std::function<void(const ImuSample&)> imu;
  std::function<void(LidarFrame&&)> frame;
  std::function<void(std::size_t, std::size_t)> progress;  ///< (messages done, total); optional
};

/// The sample of one sensor_msgs/Imu of either ROS generation (roscpp's message or ros2::Imu: the
/// same field names), stamped `stamp` [s] (its header stamp), accelerations in the recorded unit.
/// A covariance whose first element is -1 declares its vector absent (REP 145): BagError
/// "<where>: the IMU declares no angular velocity|linear acceleration (covariance[0] = -1)".
template <class ImuMessage>
ImuSample imuSampleOf(const ImuMessage& m, double stamp, const std::string& where) {
  const bool no_gyro = m.angular_velocity_covariance[0] == -1;
  if (no_gyro || m.linear_acceleration_covariance[0] == -1)
    throw BagError(where + ": the IMU declares no " +
                   (no_gyro ? "angular velocity" : "linear acceleration") +
                   " (covariance[0] = -1)");
  ImuSample s;
  s.t = stamp;
  s.gyro = Vec3(m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z);
  s.accel = Vec3(m.linear_acceleration.x, m.linear_acceleration.y, m.linear_acceleration.z);
  return s;
}

/// The decoded messages of one recording, in, and the callbacks, in header-time order, out.
class ImportStream {
 public:
  /// `config` must be valid (validate()); `callbacks.imu` and `.frame` are required.
  ImportStream(const BagImportConfig& config, BagReadCallbacks callbacks);

  /// An IMU sample with its header stamp (sample.t) and its accelerations in the recorded unit.
  /// `where` ("<file>: <topic> message <n>") names it in errors. Throws BagError for a sample
  /// more than reorder_window late, or when the unit check fails.
  void imu(ImuSample sample, const std::string& where);
  /// A decoded cloud with its scan stamp (0: unusable) before lidar_time_offset; frame.stamp is
  /// set here. Throws BagError for a frame more than reorder_window late.
  void frame(LidarFrame&& frame, double scan_stamp, const std::string& where);
  /// A cloud skipped for want of a trigger (counted).
  void untriggered() { ++lidar_.summary.untriggered; }

  /// The end of the recording (or of what is read of it): the unit check over the samples there
  /// are, the buffer flushed. `where` names the IMU topic in errors.
  void finish(const std::string& where);
  /// Forgets what is buffered and the order state of both topics (a new window of the same
  /// recording); the counts go on.
  void restart();

  /// Fills the summary's imu, lidar, points, invalid points, accel_mean_norm and gap_factor
  /// (topic, type and in_bag of imu and lidar are the caller's). Throws BagError "<file>: no usable
  /// message on <topic>" when a topic passed nothing on.
  void summarize(BagSummary& summary, std::size_t invalid_points);

 private:
  struct Pending {
    ImuSample imu;
    LidarFrame frame;
  };
  using Key = std::tuple<double, int, std::size_t>;  // stamp, IMU (0) before LiDAR (1), arrival
  /// Per-topic bookkeeping.
  struct TopicState {
    TopicSummary summary;
    std::vector<double> stamps;  // imported stamps, for rates and gaps
    double last = -1;            // last accepted stamp
    bool accept(double t);
    void finish(double gap_factor);
  };
  void push(double t, int kind, Pending&& p, const std::string& where);
  void emit(std::map<Key, Pending>::iterator it);
  void checkUnit(const std::string& where);

  BagImportConfig config_;
  BagReadCallbacks cb_;
  TopicState imu_, lidar_;
  std::map<Key, Pending> buffer_;
  std::size_t arrival_ = 0;
  double written_up_to_ = -1, newest_ = -1;
  Vec3 accel_sum_ = Vec3::Zero();
  int accel_n_ = 0;
  bool unit_checked_ = false;
  double accel_mean_norm_ = 0;
  std::size_t points_ = 0;
};

}  // namespace freeinit::bags
