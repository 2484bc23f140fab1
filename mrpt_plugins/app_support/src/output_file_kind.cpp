#include <freeinit/app_support/output_file_kind.h>
#include <zlib.h>

#include <fstream>
#include <string_view>

#include "ini_text.h"

namespace freeinit::app_support {
namespace {

constexpr std::size_t kHead = 4096;

/// The first kHead bytes of `path`, decompressed when it is gzip; nullopt if unreadable.
std::optional<std::string> head(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) return std::nullopt;
  std::string bytes(kHead, '\0');
  f.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  bytes.resize(static_cast<std::size_t>(f.gcount()));
  if (bytes.size() < 2 || static_cast<unsigned char>(bytes[0]) != 0x1f ||
      static_cast<unsigned char>(bytes[1]) != 0x8b)
    return bytes;
  // gzip: what it holds (a damaged stream gives what decompresses before the damage).
  gzFile z = gzopen(path.c_str(), "rb");
  if (z == nullptr) return bytes;
  std::string out(kHead, '\0');
  const int n = gzread(z, out.data(), static_cast<unsigned>(out.size()));
  gzclose(z);
  out.resize(n > 0 ? static_cast<std::size_t>(n) : 0);
  return out;
}

bool startsWith(std::string_view s, std::string_view prefix) {
  return s.substr(0, prefix.size()) == prefix;
}

/// An MRPT archive whose first object is of class `name` (its name written as one byte
/// 0x80 | length, then the name, with or without its namespace).
bool archiveOf(std::string_view h, std::string_view name) {
  if (h.empty()) return false;
  const auto first = static_cast<unsigned char>(h[0]);
  const std::size_t length = first & 0x7Fu;
  if ((first & 0x80u) == 0 || h.size() < 1 + length) return false;
  const std::string_view cls = h.substr(1, length);
  return cls == name || (cls.size() > name.size() && cls.substr(cls.size() - name.size()) == name &&
                         cls.substr(cls.size() - name.size() - 2, 2) == "::");
}

}  // namespace

std::optional<OutputFileKind> outputFileKind(const std::string& path) {
  const std::optional<std::string> h = head(path);
  if (!h || h->empty()) return std::nullopt;
  const std::string_view s = *h;
  if (archiveOf(s, "CSimpleMap")) return OutputFileKind::SimpleMap;
  if (startsWith(s, "ply\n") || startsWith(s, "ply\r\n")) return OutputFileKind::Ply;
  if (startsWith(s, "\x89PNG\r\n\x1a\n")) return OutputFileKind::Png;
  if (startsWith(s, "FIIDX")) return OutputFileKind::SeekIndex;
  if (startsWith(s, "t,v_l_x,")) return OutputFileKind::Velocities;
  if (startsWith(s, "# timestamp x y z qx qy qz qw")) return OutputFileKind::Trajectory;
  if (startsWith(s, "index,start_offset_s,") || startsWith(s, "# Free-Init along "))
    return OutputFileKind::StartTable;
  if (startsWith(s, "t,p_x,p_y,p_z,q_w,")) return OutputFileKind::GroundTruth;
  if (s.find('\0') != std::string_view::npos) return std::nullopt;
  const std::string_view first = firstIniLine(s);
  if (first == "[initial_state]") return OutputFileKind::InitialState;
  if (first == "[errors_wrt_ground_truth]") return OutputFileKind::TruthErrors;
  if (first == "[stream]") return OutputFileKind::StreamStats;
  return std::nullopt;
}

std::string describe(OutputFileKind kind) {
  switch (kind) {
    case OutputFileKind::SimpleMap:
      return "an MRPT simple map (a run's static map, static_map.simplemap)";
    case OutputFileKind::Ply:
      return "a PLY point cloud (a run's static map, static_map.ply)";
    case OutputFileKind::Png:
      return "a PNG image (a run's snapshot, e.g. static_map.png or velocity.png)";
    case OutputFileKind::InitialState:
      return "the initial state a run wrote (initial_state.ini)";
    case OutputFileKind::TruthErrors:
      return "the report of errors against ground truth a run wrote (errors_wrt_gt.ini)";
    case OutputFileKind::StreamStats:
      return "the statistics of a live stream (stream_stats.ini of freeinit-online)";
    case OutputFileKind::Velocities:
      return "the velocity table a run wrote (velocimeter.csv)";
    case OutputFileKind::Trajectory:
      return "the trajectory a run wrote (trajectory_tum.txt)";
    case OutputFileKind::StartTable:
      return "the table of a run at several starts (starts.csv or starts.md)";
    case OutputFileKind::SeekIndex:
      return "the seek index of a rawlog (<input>.freeinit.idx)";
    case OutputFileKind::GroundTruth:
      return "the ground truth of a simulated recording (<input>.truth.csv of freeinit-sim)";
  }
  return "?";
}

std::string outputGivenAsInput(const std::string& path, const std::string& role,
                               const std::string& expected, const std::string& instead) {
  const std::optional<OutputFileKind> kind = outputFileKind(path);
  if (!kind) return "";
  return role + " '" + path + "' is " + describe(*kind) + ", not " + expected + ": give " + instead;
}

}  // namespace freeinit::app_support
