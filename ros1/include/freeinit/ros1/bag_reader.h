// Streams the IMU and LiDAR messages of a ROS1 bag into core types, in header-time order, without
// loading the bag: a rosbag::View reads chunk by chunk and the reorder buffer shared with the ROS 2
// importer (bags/import_stream.h, BagImportConfig::reorder_window) puts the messages of both topics
// in stamp order (IMU first on ties, as the simulator writes its rawlogs).
//
// Ros1Reader reads a window of bag (receive) time: the bag's index (the connection and chunk info
// records at its end, and the index records after each chunk: a bag time and an offset per
// message) tells which chunks hold the messages of the window, and only those chunks are read
// (rosbag::View over the time range; the bag guard checks each chunk just before librosbag
// decompresses it). readBag reads the whole bag through it.
//
// Scan stamps come from the cloud headers, from a trigger topic matched by sequence number, or from
// the bag's receive time (BagImportConfig::stamp_source). The triggers are read alongside the
// clouds, up to a few seconds of bag time ahead of the cloud being matched (readBag: all of them
// first).
//
// Bad bags never import silently wrong: a missing topic, a topic of another message type, a cloud
// that does not match the configured layout, accelerations in the other unit, an IMU message
// without gyro or accelerometer data, or a message later than the reorder window throw BagError
// naming the file, the topic and the message. Messages whose stamp does not increase within their
// topic, or that are unusable (zero stamp, NaN IMU values, clouds with no valid point, no trigger),
// are skipped and counted in the summary; NaN points are dropped and counted.
//
// Corrupt bags: the file's structure is checked before librosbag reads it (bag_guard.h: the index
// when the bag is opened, each chunk before its messages are read; readBag checks the whole file
// first), each message's serialized lengths before roscpp deserializes it, and any exception left
// (bad_alloc included) becomes a BagError naming the file and the message.
#pragma once

#include <freeinit/bags/import_stream.h>
#include <freeinit/bags/recording_reader.h>
#include <freeinit/bags/static_transforms.h>
#include <freeinit/ros1/bag_guard.h>
#include <freeinit/ros1/bag_import_config.h>
#include <freeinit/types.h>

#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <utility>

namespace freeinit::ros1 {

using bags::BagError;
using bags::BagReadCallbacks;
using bags::BagSummary;
using bags::TopicSummary;
using bags::TriggerSummary;

/// A ROS 1 bag opened for import, read message by message into an ImportStream over a window of
/// its bag time.
class Ros1Reader : public bags::RecordingReader {
 public:
  /// How much of the bag's structure is checked when it is opened: the index only (each chunk is
  /// checked when a window first needs it), or the whole file at once (as the importer reads it
  /// all anyway; its errors come before any message is read).
  enum class Check { kIndex, kWholeFile };

  /// Opens `path` and checks the topics: the IMU and LiDAR topics (and the trigger topic, with
  /// stamp_source = trigger) must hold messages of the expected types. Throws BagError naming the
  /// file (a bag the guard rejects, a missing topic listing those there are, a topic of another
  /// type), std::invalid_argument for a configuration that does not validate.
  Ros1Reader(const std::string& path, const BagImportConfig& config, Check check = Check::kIndex);
  ~Ros1Reader() override;
  Ros1Reader(const Ros1Reader&) = delete;
  Ros1Reader& operator=(const Ros1Reader&) = delete;

  const std::string& path() const override;
  /// Topics, types, message counts (from the index), other topics; the trigger statistics over
  /// the triggers read so far.
  const BagSummary& summary() const override;
  /// readStaticExtrinsics of the open bag (reads the tf topic and one message of each sensor
  /// topic, and only the chunks that hold them).
  std::optional<bags::RecordedExtrinsics> staticExtrinsics() override;
  /// Starts (again) at the messages of the IMU and LiDAR topics recorded in [from, to] ([ns] UNIX
  /// bag time).
  void start(std::int64_t from = std::numeric_limits<std::int64_t>::min(),
             std::int64_t to = std::numeric_limits<std::int64_t>::max()) override;
  bool step(bags::ImportStream& stream) override;
  /// In thousandths of the bag's time span (from its index).
  std::pair<std::int64_t, std::int64_t> progress() const override;
  double lastLogTime() const override;

  /// (messages read, messages in the window) since start().
  std::pair<std::size_t, std::size_t> messages() const;
  /// NaN/inf points dropped so far.
  std::size_t invalidPoints() const;
  /// The checked structure: the index, the chunks read so far and the bytes the guard read.
  const CheckedBag& checked() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Reads `path` and calls the callbacks in stamp order (a Ros1Reader over the whole bag). Throws
/// BagError (see above) or std::invalid_argument for an invalid configuration.
BagSummary readBag(const std::string& path, const BagImportConfig& config,
                   const BagReadCallbacks& callbacks);

/// The LiDAR pose in the IMU frame from the bag's config.tf_static_topic (tf2_msgs/TFMessage),
/// linking the frame_id of the first IMU message to that of the first cloud
/// (bags/static_transforms.h); nullopt when the bag has no such topic or it does not link them.
/// Throws BagError for a topic of another type or a message that does not deserialize.
std::optional<bags::RecordedExtrinsics> readStaticExtrinsics(const std::string& path,
                                                             const BagImportConfig& config);

}  // namespace freeinit::ros1
