// Reads a rosbag2 folder: metadata.yaml and the files it lists (relative_file_paths), split
// .db3 or .mcap files, each opened by its content. Their messages are merged in log-time order
// (ties: the earlier file first), so that a recording split while messages were still arriving out
// of order reads as one. Topics are the union of the files' topics (a topic's id differs from file
// to file in .db3 files); message counts come from metadata.yaml.
//
// Errors name the folder: "<folder>: a rosbag2 folder: metadata.yaml lists x_1.db3, which is not
// in the folder", "...: metadata.yaml line 12: ...", "...: storage 'foo' is not supported",
// compressed files or messages (compression_format) are not read (decompress the recording
// first), and each file's own errors and warnings are passed on with its name.
#pragma once

#include <freeinit/ros2/bag_metadata.h>
#include <freeinit/ros2/recording.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace freeinit::ros2 {

class Rosbag2FolderReader final : public Recording {
 public:
  /// Opens the folder `folder`. Throws RecordingError.
  explicit Rosbag2FolderReader(const std::string& folder, const ReaderLimits& limits = {});
  ~Rosbag2FolderReader() override;

  void start(const ReadOptions& options) override;
  bool next(Message& message) override;

  const BagMetadata& metadata() const { return metadata_; }
  /// The split files, in order.
  const std::vector<std::unique_ptr<Recording>>& files() const { return files_; }

 private:
  BagMetadata metadata_;
  std::vector<std::unique_ptr<Recording>> files_;
  std::vector<std::vector<std::size_t>> topic_map_;  ///< [file][file's topic] -> our topic
  /// The next message of each file (empty when it has no more).
  std::vector<std::optional<Message>> heads_;
};

}  // namespace freeinit::ros2
