// A recording of either ROS generation opened for import and read message by message into an
// ImportStream (import_stream.h), over a window of its log (bag) time that the container's index
// answers without reading what lies outside: the ROS 2 reader (ros2_import.h) and the ROS 1 reader
// (ros1/bag_reader.h) implement it, and the apps read both through it.
#pragma once

#include <freeinit/bags/import_stream.h>
#include <freeinit/bags/static_transforms.h>

#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <utility>

namespace freeinit::bags {

class RecordingReader {
 public:
  virtual ~RecordingReader() = default;

  /// The file or folder read.
  virtual const std::string& path() const = 0;
  /// The topics (type, count where known), the other topics and the reader's warnings; kind is
  /// what the recording is ("a ROS 1 bag", "an MCAP file (ROS 2)", ...).
  virtual const BagSummary& summary() const = 0;
  /// The LiDAR pose in the IMU frame from config.tf_static_topic, linking the frame_id of the
  /// first IMU message to that of the first cloud; nullopt when the recording has no such topic
  /// or it does not link them. Throws BagError.
  virtual std::optional<RecordedExtrinsics> staticExtrinsics() = 0;
  /// Starts (again) at the messages logged in [from, to] ([ns] UNIX).
  virtual void start(std::int64_t from = std::numeric_limits<std::int64_t>::min(),
                     std::int64_t to = std::numeric_limits<std::int64_t>::max()) = 0;
  /// Reads, decodes and feeds one message to `stream`; false at the end of the window. Throws
  /// BagError naming the file, the topic and the message.
  virtual bool step(ImportStream& stream) = 0;
  /// (done, total) for a progress bar, in [ns] of log time: how far past the recording's first
  /// message the last message read was logged, and the recording's span; (0, 0) when the span is
  /// unknown.
  virtual std::pair<std::int64_t, std::int64_t> progress() const = 0;
  /// [s] UNIX log time of the last message read.
  virtual double lastLogTime() const = 0;
};

}  // namespace freeinit::bags
