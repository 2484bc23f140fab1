// Reads the messages of one MCAP file (https://mcap.dev/spec), as rosbag2 and other ROS 2 tools
// write it: chunks uncompressed, zstd or lz4, with or without the summary section at the end.
//
// Opening reads the footer and, when the file has one, the summary section: schemas, channels,
// statistics and the chunk indexes (where each chunk is and the log times it spans). Reading a
// window [start, end] then reads and decompresses only the chunks that overlap it. A file without
// a summary (a recorder killed mid-write leaves none, some writers omit it) is scanned once at
// opening instead, which also finds where it stops being whole: a file that ends inside a record
// is read up to the last whole record, with a warning ("the file ends at byte B, inside record N
// ...: read what is whole"), not an error.
//
// Messages come in log-time order (ties in file order), merged across chunks whose times overlap;
// a file whose messages are not in chunks is read in file order (ordered() is false, with a
// warning). Topics are the channels (merged when they share topic, type and encoding), their type
// the channel's schema name.
//
// Every length in the file is checked against the bytes that hold it before it is used; chunks
// are bounded by ReaderLimits::max_chunk_bytes and decompressed into a buffer that grows with the
// output, so a corrupt file cannot make the reader allocate much beyond its own size. Corrupt
// structure, an unsupported compression and a failed CRC throw RecordingError
// "<path>: an MCAP file (ROS 2): <what, where>".
#pragma once

#include <freeinit/ros2/recording.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

namespace freeinit::ros2 {

class McapReader final : public Recording {
 public:
  /// Opens `path`. Throws RecordingError (a file that cannot be opened, is not MCAP, or whose
  /// structure is corrupt).
  explicit McapReader(const std::string& path, const ReaderLimits& limits = {});
  ~McapReader() override;

  void start(const ReadOptions& options) override;
  bool next(Message& message) override;

  /// True when the summary section's chunk indexes are used; false when the file was scanned.
  bool indexed() const;
  /// Chunks holding messages.
  std::size_t chunkCount() const;
  /// [bytes] read from the file since it was opened: what a window costs.
  std::uint64_t bytesRead() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace freeinit::ros2
