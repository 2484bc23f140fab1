// The front door: what a path is, recognised by its content (not its name), and the reader for it.
//   a file starting with "\x89MCAP0\r\n"         an MCAP file            -> McapReader
//   a file starting with "SQLite format 3\0"     a rosbag2 .db3          -> SqliteBagReader
//   a folder holding metadata.yaml (or that file) a rosbag2 folder       -> Rosbag2FolderReader
//   a file starting with "#ROSBAG V"             a ROS 1 bag             (not read here)
#pragma once

#include <freeinit/ros2/recording.h>

#include <memory>
#include <string>

namespace freeinit::ros2 {

enum class RecordingKind {
  kMissing,        ///< nothing at the path
  kMcap,           ///< an MCAP file
  kSqlite,         ///< an SQLite file (a rosbag2 .db3)
  kRosbag2Folder,  ///< a folder with metadata.yaml
  kPlainFolder,    ///< a folder without metadata.yaml
  kRos1Bag,        ///< a ROS 1 bag
  kUnknown,        ///< a file of none of these kinds (or empty, or unreadable)
};

/// Looks at the first bytes of a file, or into a folder. Never throws.
RecordingKind identifyRecording(const std::string& path);

/// "an MCAP file (ROS 2)", "a rosbag2 SQLite file (.db3)", "a rosbag2 folder", "a ROS 1 bag", ...
std::string describe(RecordingKind kind);

/// Opens the recording at `path` (a file, a rosbag2 folder, or its metadata.yaml). Throws
/// RecordingError with one line naming the path and what is wrong: nothing there, a ROS 1 bag, a
/// folder without metadata.yaml (listing the recordings it holds), a file of another kind (showing
/// its first bytes), or the error of the reader.
std::unique_ptr<Recording> openRecording(const std::string& path, const ReaderLimits& limits = {});

}  // namespace freeinit::ros2
