// What a file given on a command line is, from its first bytes (not its name): so that
// `freeinit <input.rawlog>` and `freeinit <config.ini> <input.rawlog>` tell a configuration from a
// rawlog or a ROS recording, and a file that is none of them is refused with one line naming it.
#pragma once

#include <string>

namespace freeinit::app_support {

enum class FileKind {
  Unreadable,  ///< missing or cannot be opened (the reader of the file says why)
  Empty,
  Rawlog,         ///< gzip data, or an MRPT archive (its first object's class name)
  RosBag,         ///< "#ROSBAG V2.0"
  Mcap,           ///< "\x89MCAP0\r\n": an MCAP file (ROS 2)
  Sqlite,         ///< "SQLite format 3": a rosbag2 .db3 (ROS 2)
  Rosbag2Folder,  ///< a folder with metadata.yaml (ROS 2)
  Folder,         ///< another folder
  Ini,     ///< text whose first line that is not blank or a comment is a [section] or key = value
  Text,    ///< other text
  Binary,  ///< none of the above
};

/// Looks at the first 4 KiB of `path` (a folder: whether it holds metadata.yaml).
FileKind fileKind(const std::string& path);

/// "an MRPT rawlog", "an INI configuration file", ... (for messages).
std::string describe(FileKind kind);

/// A rawlog or a recording the apps read straight in (an MCAP file, a .db3, a rosbag2 folder; a
/// ROS 1 bag when built with FREEINIT_WITH_ROSBAG).
bool isReadableInput(FileKind kind);

}  // namespace freeinit::app_support
