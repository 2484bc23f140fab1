// ROS 2 recordings (an MCAP file, a rosbag2 folder, a single .db3; ros2/open_recording.h) into
// core types with the settings, checks and summary of the ROS 1 importer: sensor_msgs/msg/Imu and
// sensor_msgs/msg/PointCloud2 in CDR, decoded by the codec both generations share, in header-time
// order through the same reorder buffer (import_stream.h). Scan stamps from the cloud's header or
// the recording's log time (stamp_source = trigger is ROS 1 only: ROS 2 headers have no seq).
#pragma once

#include <freeinit/bags/cloud_codec.h>
#include <freeinit/bags/import_config.h>
#include <freeinit/bags/import_stream.h>
#include <freeinit/bags/recording_reader.h>
#include <freeinit/bags/static_transforms.h>
#include <freeinit/ros2/recording.h>

#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>

namespace freeinit::bags {

/// [s] a time in ns as ROS computes seconds (sec + 1e-9 nsec): the same double for both ROS
/// generations.
double rosSeconds(std::int64_t ns);

/// A ROS 2 recording opened for import, read message by message into an ImportStream.
class Ros2Reader : public RecordingReader {
 public:
  /// Opens `path` and checks the topics: both must exist with the expected types, encoded in CDR.
  /// Throws BagError naming the file and what it is for: a recording that does not open
  /// (ros2::openRecording's messages), a missing topic (listing those there are with their types),
  /// a topic of another type, stamp_source = trigger; std::invalid_argument for a configuration
  /// that does not validate.
  Ros2Reader(const std::string& path, const BagImportConfig& config);
  ~Ros2Reader() override;
  Ros2Reader(const Ros2Reader&) = delete;
  Ros2Reader& operator=(const Ros2Reader&) = delete;

  const ros2::Recording& recording() const { return *rec_; }
  const std::string& path() const override;
  /// The topics (type, count where known), the other topics and the reader's warnings.
  const BagSummary& summary() const override { return summary_; }

  /// The LiDAR pose in the IMU frame from config.tf_static_topic, linking the frame_id of the
  /// first IMU message to that of the first cloud; nullopt when the recording has no such topic
  /// or it does not link them. Reads the whole tf topic (a few messages: the index skips the rest)
  /// and one message of each sensor topic.
  std::optional<RecordedExtrinsics> staticExtrinsics() override;

  /// Starts (again) at the messages logged in [from, to] ([ns] UNIX).
  void start(std::int64_t from = std::numeric_limits<std::int64_t>::min(),
             std::int64_t to = std::numeric_limits<std::int64_t>::max()) override;
  /// Reads, decodes and feeds one message to `stream`; false at the end. Throws BagError naming
  /// the file, the topic and the message.
  bool step(ImportStream& stream) override;
  std::pair<std::int64_t, std::int64_t> progress() const override;
  /// NaN/inf points dropped so far.
  std::size_t invalidPoints() const { return stats_.invalid_points; }
  /// Messages read per topic so far.
  std::size_t imuRead() const { return imu_read_; }
  std::size_t cloudsRead() const { return clouds_read_; }
  /// [s] UNIX log time of the last message read (rosSeconds).
  double lastLogTime() const override { return rosSeconds(last_log_time_); }

 private:
  /// The frame_id of the first message of `topic` (its header).
  std::string firstFrameId(std::size_t topic, bool imu);

  BagImportConfig config_;
  std::unique_ptr<ros2::Recording> rec_;
  std::size_t imu_topic_ = 0, lidar_topic_ = 0;
  BagSummary summary_;
  DecodeStats stats_;
  ros2::Message msg_;
  std::size_t imu_read_ = 0, clouds_read_ = 0;
  std::int64_t last_log_time_ = 0;
};

/// The whole recording through the callbacks, as ros1::readBag reads a ROS 1 bag. Throws BagError
/// (see Ros2Reader) or std::invalid_argument.
BagSummary readRos2Recording(const std::string& path, const BagImportConfig& config,
                             const BagReadCallbacks& callbacks);

}  // namespace freeinit::bags
