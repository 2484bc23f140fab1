// Streams the IMU and LiDAR messages of a ROS1 bag into core types, in header-time order, without
// loading the bag: a rosbag::View reads chunk by chunk and the reorder buffer shared with the ROS 2
// importer (bags/import_stream.h, BagImportConfig::reorder_window) puts the messages of both topics
// in stamp order (IMU first on ties, as the simulator writes its rawlogs).
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

#include <freeinit/bags/import_stream.h>
#include <freeinit/bags/static_transforms.h>
#include <freeinit/ros1/bag_import_config.h>
#include <freeinit/types.h>

#include <optional>
#include <string>

namespace freeinit::ros1 {

using bags::BagError;
using bags::BagReadCallbacks;
using bags::BagSummary;
using bags::TopicSummary;
using bags::TriggerSummary;

/// Reads `path` and calls the callbacks in stamp order. Throws BagError (see above) or
/// std::invalid_argument for an invalid configuration.
BagSummary readBag(const std::string& path, const BagImportConfig& config,
                   const BagReadCallbacks& callbacks);

/// The LiDAR pose in the IMU frame from the bag's config.tf_static_topic (tf2_msgs/TFMessage),
/// linking the frame_id of the first IMU message to that of the first cloud
/// (bags/static_transforms.h); nullopt when the bag has no such topic or it does not link them.
/// Throws BagError for a topic of another type or a message that does not deserialize.
std::optional<bags::RecordedExtrinsics> readStaticExtrinsics(const std::string& path,
                                                             const BagImportConfig& config);

}  // namespace freeinit::ros1
