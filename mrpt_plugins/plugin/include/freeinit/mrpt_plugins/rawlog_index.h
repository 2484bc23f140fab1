// The seek index of a rawlog: where each top-level record starts in the decompressed stream, its
// timestamp and kind, and access points into the gzip stream, so that a reader reaches any
// record by decompressing at most `spacing` bytes and deserializing nothing before it.
//
// Why this design: a rawlog is a gzip stream of MRPT objects with no lengths (objects nest
// inline), so a record's extent is known only by deserializing it, and gzip itself cannot seek.
// Decompressing dominates reading (deserializing adds under 10 % at 60,000 points per frame), so
// skipping records without deserializing them saves little; the access points save all of it.
// An access point is a deflate block boundary: its position in the file (and bit), its position in
// the decompressed stream and the 32 KiB before it (deflate's dictionary), stored compressed.
//
// File "<rawlog>.freeinit.idx" beside the rawlog or, when that folder is not writable, in the
// cache folder. It names the rawlog's size, modification time and a checksum of its first and
// last 64 KiB: any change makes it stale and it is rebuilt. It may cover the first records only
// (a reader that stopped early); later reads extend it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace freeinit::mrpt_plugins {

/// A place where decompression can resume.
struct AccessPoint {
  std::uint64_t in = 0;               ///< [bytes] file offset of the first byte not fully consumed
  int bits = 0;                       ///< unused bits of the byte before `in` (0..7)
  std::uint64_t out = 0;              ///< [bytes] offset in the decompressed stream
  std::vector<unsigned char> window;  ///< up to 32 KiB of output before `out`
};

/// What the index knows of one top-level record.
struct IndexedRecord {
  enum Kind : std::uint8_t {
    kOther = 0,
    kImu = 1,
    kPointCloud = 2,
    kObservation = 3,
    kSensoryFrame = 4,
    kAction = 5
  };
  std::uint64_t offset = 0;  ///< [bytes] start in the decompressed stream
  std::int64_t ticks = 0;    ///< mrpt::Clock ticks of its timestamp (sensory frame: the latest)
  std::uint8_t kind = kOther;
  bool hasTime() const { return kind != kAction && kind != kOther; }
};

/// Identifies the rawlog an index was built from.
struct RawlogIdentity {
  std::uint64_t size = 0;
  std::int64_t mtime_ns = 0;
  std::uint32_t head_crc = 0, tail_crc = 0;  ///< CRC-32 of the first / last 64 KiB
  bool operator==(const RawlogIdentity& o) const {
    return size == o.size && mtime_ns == o.mtime_ns && head_crc == o.head_crc &&
           tail_crc == o.tail_crc;
  }
};
/// Throws std::runtime_error if the file cannot be read.
RawlogIdentity rawlogIdentity(const std::string& rawlog);

struct RawlogIndex {
  static constexpr std::uint64_t kDefaultSpacing = 8u << 20;  ///< [bytes] between access points

  RawlogIdentity identity;
  bool gzip = true;
  std::uint64_t spacing = kDefaultSpacing;
  std::vector<AccessPoint> points;     ///< increasing `out`
  std::vector<IndexedRecord> records;  ///< records 0 .. n-1
  std::uint64_t covered = 0;           ///< [bytes] end of the last record in `records`
  bool complete = false;               ///< `records` are all the file's records

  /// The last access point at or before `offset` (nullptr if none).
  const AccessPoint* pointBefore(std::uint64_t offset) const;
};

/// "<rawlog>.freeinit.idx", and its place in the cache folder ($XDG_CACHE_HOME/freeinit, else
/// ~/.cache/freeinit; `cache_dir` if not empty), named after the rawlog's absolute path.
std::string indexPathBeside(const std::string& rawlog);
std::string indexPathInCache(const std::string& rawlog, const std::string& cache_dir);

/// Loads an index; false if it is missing, not a regular file (a FIFO or a device is never
/// opened for reading in a way that blocks), larger than the rawlog it claims to index, unreadable,
/// of another format, not of `identity`, or inconsistent with the recording (access points
/// beyond the file or out of order, records out of order or beyond what it covers).
bool loadRawlogIndex(const std::string& path, const RawlogIdentity& identity, RawlogIndex& out);
/// Writes atomically (temporary file + rename). Throws std::runtime_error, also when something
/// that is not a regular file (a link, a FIFO, a device, a folder) has the index's name: it is not
/// ours.
void saveRawlogIndex(const std::string& path, const RawlogIndex& index);

}  // namespace freeinit::mrpt_plugins
