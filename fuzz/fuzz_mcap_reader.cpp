// Fuzz harness: a whole MCAP file through the ROS 2 reader (ros2/mcap_reader.h), with the CDR
// decoder on every message of the three types the importer reads. Chunk CRCs are not checked (the
// fuzzer cannot fix them up, and they would stop it at the first chunk it changes); chunks are
// bounded to 1 MB and 32 MB at once, so that no input may allocate much.
// Invariants:
//   - messages name a topic of the file; in log-time order when the reader says so;
//   - a file opened by scanning it (no usable summary) reads without error, and exactly the
//     messages the scan counted per topic;
//   - reading from the middle log time on returns exactly the messages at or after it that
//     reading everything returned, in the same order (a window seeks through the chunk index).
#include <freeinit/ros2/mcap_reader.h>
#include <freeinit/ros2/message_decoding.h>

#include <optional>
#include <tuple>
#include <vector>

#include "harness.h"

namespace freeinit::fuzz {
namespace {

using Seen = std::tuple<std::int64_t, std::size_t, std::vector<std::uint8_t>>;

// Reads with `options`; decodes the messages of known types (their errors are expected).
std::vector<Seen> readAll(ros2::Recording& r, const ros2::ReadOptions& options,
                          std::size_t& decoded) {
  std::vector<Seen> seen;
  r.start(options);
  ros2::Message m;
  while (r.next(m)) {
    if (m.topic >= r.topics().size()) broken("a message of an unknown topic");
    if (r.ordered() && !seen.empty() && m.log_time < std::get<0>(seen.back()))
      broken("messages out of log-time order");
    const std::string& type = r.topics()[m.topic].type;
    try {
      if (type == ros2::kImuType) ros2::decodeImu(m.data);
      if (type == ros2::kPointCloud2Type) {
        const ros2::PointCloud2 c = ros2::decodePointCloud2(m.data);
        if (c.data.size() > m.data.size() || c.fields.size() > m.data.size() / 13)
          broken("a decoded cloud larger than its message");
      }
      if (type == ros2::kTFMessageType) ros2::decodeTFMessage(m.data);
      ++decoded;
    } catch (const ros2::CdrError&) {
    }
    seen.emplace_back(m.log_time, m.topic, std::move(m.data));
  }
  return seen;
}

}  // namespace

std::string fuzzOne(const std::uint8_t* data, std::size_t size) {
  std::string error;
  const std::string path = writeInput("mcap_reader", ".mcap", data, size, error);
  if (path.empty()) return error;
  ros2::ReaderLimits limits;
  limits.max_chunk_bytes = std::uint64_t{1} << 20;
  limits.max_loaded_bytes = std::uint64_t{32} << 20;
  limits.verify_crc = false;
  std::optional<ros2::McapReader> reader;
  try {
    reader.emplace(path, limits);
  } catch (const ros2::RecordingError& e) {
    return "error: " + firstLine(e.what());
  }
  ros2::McapReader& r = *reader;
  std::size_t decoded = 0;
  std::vector<Seen> all;
  try {
    all = readAll(r, {}, decoded);
  } catch (const ros2::RecordingError& e) {
    if (!r.indexed()) broken("a scanned file failed to read");
    return "error: reading: " + firstLine(e.what());
  }
  if (!r.indexed()) {
    std::vector<std::uint64_t> counts(r.topics().size(), 0);
    for (const Seen& s : all) ++counts[std::get<1>(s)];
    for (std::size_t t = 0; t < counts.size(); ++t)
      if (r.topics()[t].message_count != counts[t]) broken("read counts differ from the scan's");
  }
  if (all.size() >= 2) {
    ros2::ReadOptions window;
    window.start = std::get<0>(all[all.size() / 2]);
    std::vector<Seen> expected;
    for (const Seen& s : all)
      if (std::get<0>(s) >= window.start) expected.push_back(s);
    std::size_t ignored = 0;
    try {
      if (readAll(r, window, ignored) != expected)
        broken("a window reads other messages than skipping");
    } catch (const ros2::RecordingError&) {
      broken("a window failed where reading everything did not");
    }
  }
  return "ok: " + std::to_string(all.size()) + " messages (" + std::to_string(decoded) +
         " decoded), " + std::to_string(r.topics().size()) + " topics, " +
         (r.indexed() ? "indexed" : "scanned") + ", " + std::to_string(r.warnings().size()) +
         " warning(s)";
}

}  // namespace freeinit::fuzz
