// What a file given on a command line is, from its first bytes (not its name): so that
// `freeinit <input.rawlog>` and `freeinit <config.ini> <input.rawlog>` tell a configuration from a
// rawlog, and a file that is neither is refused with one line naming it.
#pragma once

#include <string>

namespace freeinit::app_support {

enum class FileKind {
  Unreadable,  ///< missing or cannot be opened (the reader of the file says why)
  Empty,
  Rawlog,  ///< gzip data, or an MRPT archive (its first object's class name)
  RosBag,  ///< "#ROSBAG V2.0"
  Ini,     ///< text whose first line that is not blank or a comment is a [section] or key = value
  Text,    ///< other text
  Binary,  ///< none of the above
};

/// Looks at the first 4 KiB of `path`.
FileKind fileKind(const std::string& path);

/// "an MRPT rawlog", "an INI configuration file", ... (for messages).
std::string describe(FileKind kind);

}  // namespace freeinit::app_support
