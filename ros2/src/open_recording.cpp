#include <freeinit/ros2/mcap_reader.h>
#include <freeinit/ros2/open_recording.h>
#include <freeinit/ros2/rosbag2_folder_reader.h>
#include <freeinit/ros2/sqlite_bag_reader.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <vector>

namespace freeinit::ros2 {
namespace {

namespace fs = std::filesystem;

constexpr char kMcapMagic[] = "\x89MCAP0\r\n";
constexpr char kSqliteMagic[] = "SQLite format 3";  // and its NUL: 16 bytes
constexpr char kRos1Magic[] = "#ROSBAG V";

std::string firstBytes(const std::string& path, std::size_t n) {
  std::ifstream in(path, std::ios::binary);
  std::string bytes(n, '\0');
  in.read(bytes.data(), static_cast<std::streamsize>(n));
  bytes.resize(static_cast<std::size_t>(std::max<std::streamsize>(in.gcount(), 0)));
  return bytes;
}

bool startsWith(const std::string& bytes, const char* magic, std::size_t n) {
  return bytes.size() >= n && std::memcmp(bytes.data(), magic, n) == 0;
}

// The first 8 bytes of a file in hexadecimal and as text ('.' for what is not printable): what
// the user has instead of a recording.
std::string showBytes(const std::string& bytes) {
  const char* digits = "0123456789abcdef";
  std::string hex, text;
  for (const char ch : bytes.substr(0, 8)) {
    const auto c = static_cast<unsigned char>(ch);
    hex += (hex.empty() ? "" : " ");
    hex += digits[c >> 4];
    hex += digits[c & 15];
    text += (c >= 0x20 && c < 0x7f) ? static_cast<char>(c) : '.';
  }
  return hex + " (\"" + text + "\"";
}

// The recordings a folder holds, by name.
std::vector<std::string> recordingsIn(const fs::path& dir) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string ext = e.path().extension().string();
    if (e.is_regular_file(ec) && (ext == ".db3" || ext == ".mcap"))
      names.push_back(e.path().filename().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

}  // namespace

RecordingKind identifyRecording(const std::string& path) {
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (ec || !fs::exists(st)) return RecordingKind::kMissing;
  if (fs::is_directory(st))
    return fs::is_regular_file(fs::path(path) / "metadata.yaml", ec) ? RecordingKind::kRosbag2Folder
                                                                     : RecordingKind::kPlainFolder;
  if (fs::path(path).filename() == "metadata.yaml") return RecordingKind::kRosbag2Folder;
  const std::string head = firstBytes(path, 16);
  if (startsWith(head, kMcapMagic, 8)) return RecordingKind::kMcap;
  if (startsWith(head, kSqliteMagic, 16)) return RecordingKind::kSqlite;
  if (startsWith(head, kRos1Magic, std::strlen(kRos1Magic))) return RecordingKind::kRos1Bag;
  return RecordingKind::kUnknown;
}

std::string describe(RecordingKind kind) {
  switch (kind) {
    case RecordingKind::kMissing:
      return "nothing (no such file or folder)";
    case RecordingKind::kMcap:
      return "an MCAP file (ROS 2)";
    case RecordingKind::kSqlite:
      return "a rosbag2 SQLite file (.db3)";
    case RecordingKind::kRosbag2Folder:
      return "a rosbag2 folder";
    case RecordingKind::kPlainFolder:
      return "a folder without metadata.yaml";
    case RecordingKind::kRos1Bag:
      return "a ROS 1 bag";
    case RecordingKind::kUnknown:
      break;
  }
  return "not a recording";
}

std::unique_ptr<Recording> openRecording(const std::string& path, const ReaderLimits& limits) {
  switch (identifyRecording(path)) {
    case RecordingKind::kMissing:
      throw RecordingError(path + ": no such file or folder");
    case RecordingKind::kMcap:
      return std::make_unique<McapReader>(path, limits);
    case RecordingKind::kSqlite:
      return std::make_unique<SqliteBagReader>(path);
    case RecordingKind::kRosbag2Folder:
      return std::make_unique<Rosbag2FolderReader>(fs::path(path).filename() == "metadata.yaml"
                                                       ? fs::path(path).parent_path().string()
                                                       : path,
                                                   limits);
    case RecordingKind::kPlainFolder: {
      const std::vector<std::string> held = recordingsIn(path);
      if (held.empty())
        throw RecordingError(path +
                             ": a folder without metadata.yaml or any .db3 or .mcap file: "
                             "not a rosbag2 recording");
      std::string list;
      for (const std::string& n : held) list += (list.empty() ? "" : ", ") + n;
      throw RecordingError(
          path + ": a rosbag2 folder without metadata.yaml (open its files one by one: " + list +
          ")");
    }
    case RecordingKind::kRos1Bag:
      throw RecordingError(path + ": a ROS 1 bag (" + firstBytes(path, 12) +
                           "), not a ROS 2 recording: it is read by the ROS 1 importer");
    case RecordingKind::kUnknown:
      break;
  }
  const std::string head = firstBytes(path, 16);
  if (head.empty()) throw RecordingError(path + ": an empty file, not a recording");
  throw RecordingError(path + ": not a ROS 2 recording: it starts with " + showBytes(head) +
                       "; an MCAP file starts with \\x89MCAP0\\r\\n, a rosbag2 .db3 with "
                       "'SQLite format 3')");
}

}  // namespace freeinit::ros2
