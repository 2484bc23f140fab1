#include <freeinit/app_support/file_kind.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <string_view>

#include "ini_text.h"

namespace freeinit::app_support {
namespace {

bool isClassNameChar(unsigned char c) { return std::isalnum(c) != 0 || c == '_' || c == ':'; }

// An MRPT archive starts with its first object's class name, written as one byte 0x80 | length
// and the name ("\x9amrpt::obs::CObservationIMU").
bool isMrptArchive(std::string_view head) {
  if (head.empty()) return false;
  const auto first = static_cast<unsigned char>(head[0]);
  const std::size_t length = first & 0x7Fu;
  if ((first & 0x80u) == 0 || length == 0 || head.size() < 1 + length) return false;
  return std::all_of(head.begin() + 1, head.begin() + 1 + static_cast<std::ptrdiff_t>(length),
                     [](char c) { return isClassNameChar(static_cast<unsigned char>(c)); });
}

// A section header or a key = value as the first line that is not a comment; blank lines and
// comments only: every key at its default.
bool isIni(std::string_view text) {
  const std::string_view line = firstIniLine(text);
  return line.empty() || line[0] == '[' || line.find('=') != std::string_view::npos;
}

}  // namespace

FileKind fileKind(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    return std::filesystem::is_regular_file(std::filesystem::path(path) / "metadata.yaml", ec)
               ? FileKind::Rosbag2Folder
               : FileKind::Folder;
  std::ifstream f(path, std::ios::binary);
  if (!f) return FileKind::Unreadable;
  std::string head(4096, '\0');
  f.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(f.gcount()));
  if (head.empty()) return FileKind::Empty;
  if (head.size() >= 2 && static_cast<unsigned char>(head[0]) == 0x1f &&
      static_cast<unsigned char>(head[1]) == 0x8b)
    return FileKind::Rawlog;
  if (isMrptArchive(head)) return FileKind::Rawlog;
  if (head.rfind("#ROSBAG", 0) == 0) return FileKind::RosBag;
  if (head.rfind("\x89MCAP0\r\n", 0) == 0) return FileKind::Mcap;
  if (head.compare(0, 16, std::string("SQLite format 3\0", 16)) == 0) return FileKind::Sqlite;
  if (head.find('\0') != std::string::npos) return FileKind::Binary;
  return isIni(head) ? FileKind::Ini : FileKind::Text;
}

std::string describe(FileKind kind) {
  switch (kind) {
    case FileKind::Unreadable:
      return "not readable";
    case FileKind::Empty:
      return "empty";
    case FileKind::Rawlog:
      return "an MRPT rawlog";
    case FileKind::RosBag:
      return "a ROS 1 bag";
    case FileKind::Mcap:
      return "an MCAP file (ROS 2)";
    case FileKind::Sqlite:
      return "an SQLite file (a rosbag2 .db3, ROS 2)";
    case FileKind::Rosbag2Folder:
      return "a rosbag2 folder (ROS 2)";
    case FileKind::Folder:
      return "a folder without metadata.yaml (not a rosbag2 folder)";
    case FileKind::Ini:
      return "an INI configuration file";
    case FileKind::Text:
      return "a text file";
    case FileKind::Binary:
      return "binary data, neither gzip nor an MRPT archive";
  }
  return "?";
}

bool isReadableInput(FileKind kind) {
#ifdef FREEINIT_WITH_ROSBAG
  if (kind == FileKind::RosBag) return true;
#endif
  return kind == FileKind::Rawlog || kind == FileKind::Mcap || kind == FileKind::Sqlite ||
         kind == FileKind::Rosbag2Folder;
}

}  // namespace freeinit::app_support
