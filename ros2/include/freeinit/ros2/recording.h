// A ROS 2 recording opened for reading: its topics and a stream of its serialized messages.
// Implemented by McapReader (one .mcap file), SqliteBagReader (one rosbag2 .db3 file) and
// Rosbag2FolderReader (a rosbag2 folder: metadata.yaml and its split files); openRecording
// (open_recording.h) picks the right one from the content. Messages are serialized as their topic's
// `encoding` says ("cdr" for ROS 2); message_decoding.h decodes the types the importer reads.
//
// Reading: start(options) (again at any time to restart), then next() until it returns false. A
// window [start, end] of log times is read at the cost of the window, not of the file, where the
// recording has an index: an MCAP file's chunk indexes, the timestamp index of a .db3.
#pragma once

#include <freeinit/ros2/recording_error.h>

#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace freeinit::ros2 {

/// One topic of a recording.
struct TopicInfo {
  std::string name;      ///< e.g. "/imu/data"
  std::string type;      ///< message type, e.g. "sensor_msgs/msg/Imu" ("" if the file names none)
  std::string encoding;  ///< serialization, "cdr" for ROS 2 messages
  /// Messages on the topic, where the recording says (MCAP statistics or a full scan,
  /// metadata.yaml); a .db3 on its own does not count them.
  std::optional<std::uint64_t> message_count;
};

/// One serialized message.
struct Message {
  std::size_t topic = 0;           ///< index into Recording::topics()
  std::int64_t log_time = 0;       ///< [ns] UNIX time the recorder received it
  std::vector<std::uint8_t> data;  ///< the serialized message (CDR: with its 4-byte header)
};

/// What to read. Log times are in [start, end], both included.
struct ReadOptions {
  std::int64_t start = std::numeric_limits<std::int64_t>::min();  ///< [ns] UNIX
  std::int64_t end = std::numeric_limits<std::int64_t>::max();    ///< [ns] UNIX
  std::vector<std::size_t> topics;  ///< indices into Recording::topics(); empty: every topic
};

/// Bounds on what a corrupt file can make a reader allocate. Every length in a file is checked
/// against the bytes that hold it; these bound what decompression may produce.
struct ReaderLimits {
  /// [bytes] largest MCAP chunk accepted, compressed or decompressed. Recorders write chunks of
  /// 1-4 MB and one message per chunk above that: 256 MB is 5 million 48-byte points.
  std::uint64_t max_chunk_bytes = std::uint64_t{256} << 20;
  /// [bytes] most decompressed MCAP chunk data held at once. Reading in log-time order holds the
  /// chunks whose time spans overlap; recorders write chunks one after the other in time, so one
  /// or two at once. A file whose chunks all span the whole recording would need all of it.
  std::uint64_t max_loaded_bytes = std::uint64_t{1} << 30;
  bool verify_crc = true;  ///< check MCAP chunk CRCs (where the writer computed them)
};

/// [ns] first and last log times of a recording.
struct TimeRange {
  std::int64_t first = 0;
  std::int64_t last = 0;
};

class Recording {
 public:
  virtual ~Recording() = default;
  Recording(const Recording&) = delete;
  Recording& operator=(const Recording&) = delete;

  /// The file or folder as given to the constructor.
  const std::string& path() const { return path_; }
  /// What it is, e.g. "an MCAP file (ROS 2)": the second part of error messages.
  const std::string& kind() const { return kind_; }
  const std::vector<TopicInfo>& topics() const { return topics_; }
  /// First and last log times, where the recording says or an index tells cheaply.
  const std::optional<TimeRange>& timeRange() const { return time_range_; }
  /// True when next() returns messages in non-decreasing log time (ties in file order); false
  /// when in file order (an MCAP file without chunk indexes whose messages are not in chunks).
  bool ordered() const { return ordered_; }
  /// Things the user should know that did not stop reading, one line each, e.g. "the file ends
  /// inside record 97 at byte 29456: read what is whole".
  const std::vector<std::string>& warnings() const { return warnings_; }

  /// The index of topic `name`. Throws RecordingError "<path>: topic X not found; the recording
  /// has: ..." (listing every topic with its type), "<path>: topic X has type A, expected B" when
  /// `expected_type` is not empty and differs, or "<path>: topic X is encoded as 'json'; only
  /// 'cdr' is read".
  std::size_t topic(const std::string& name, const std::string& expected_type = "") const;
  /// "name (type)" of every topic, comma-separated.
  std::string topicList() const;

  /// Starts reading (or starts again) with `options`. Throws RecordingError for a topic index out
  /// of range.
  virtual void start(const ReadOptions& options) = 0;
  /// The next message; false at the end. Throws RecordingError on a corrupt file. Without a call
  /// to start(), reads everything.
  virtual bool next(Message& message) = 0;

 protected:
  Recording(std::string path, std::string kind) : path_(std::move(path)), kind_(std::move(kind)) {}
  /// A RecordingError "<path>: <kind>: <what>".
  RecordingError error(const std::string& what) const;
  /// Checks the topic indices of `options`.
  void checkOptions(const ReadOptions& options) const;

  std::vector<TopicInfo> topics_;
  std::optional<TimeRange> time_range_;
  bool ordered_ = true;
  std::vector<std::string> warnings_;

 private:
  std::string path_;
  std::string kind_;
};

}  // namespace freeinit::ros2
