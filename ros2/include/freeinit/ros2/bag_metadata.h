// The keys of a rosbag2 folder's metadata.yaml that reading it needs (rosbag2 versions 4 to 9,
// Foxy to Jazzy and later):
//   rosbag2_bagfile_information:
//     version, storage_identifier (sqlite3 | mcap), relative_file_paths (the split files, in
//     order), topics_with_message_count (topic_metadata: name, type, serialization_format;
//     message_count), starting_time.nanoseconds_since_epoch, duration.nanoseconds,
//     compression_format, compression_mode
// Other keys (files, custom_data, QoS profiles in either form, type hashes, ...) are skipped.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace freeinit::ros2 {

struct BagMetadata {
  int version = 0;
  std::string storage_identifier;                ///< "sqlite3", "mcap" ("" if not given)
  std::vector<std::string> relative_file_paths;  ///< in recording order
  struct Topic {
    std::string name;
    std::string type;
    std::string serialization_format;
    std::uint64_t message_count = 0;
  };
  std::vector<Topic> topics;
  std::optional<std::int64_t> starting_time;  ///< [ns] UNIX
  std::optional<std::int64_t> duration;       ///< [ns]
  std::string compression_format;             ///< "" when the files are not compressed
  std::string compression_mode;               ///< "file" or "message" (any case) when they are
};

/// Parses the text of a metadata.yaml. Throws std::runtime_error "line N: <what is wrong>" (or
/// naming the missing key).
BagMetadata parseBagMetadata(const std::string& text);

}  // namespace freeinit::ros2
