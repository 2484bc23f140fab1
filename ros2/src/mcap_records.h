// The MCAP records the reader uses (https://mcap.dev/spec), parsed from bytes in memory with every
// length checked against the bytes that hold it. A record is an opcode (uint8), the length of its
// body (uint64) and the body; integers are little endian; a string is a uint32 byte count and the
// bytes; a map or an array is a uint32 byte count and its entries.
#pragma once

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace freeinit::ros2::mcap {

enum Opcode : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kAttachment = 0x09,
  kAttachmentIndex = 0x0A,
  kStatistics = 0x0B,
  kMetadata = 0x0C,
  kMetadataIndex = 0x0D,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

/// "\x89MCAP0\r\n", at the start and at the end of a file.
inline constexpr std::uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
inline constexpr std::size_t kMagicBytes = 8;
inline constexpr std::size_t kRecordHeaderBytes = 9;  ///< opcode + body length
inline constexpr std::size_t kFooterBodyBytes = 20;
inline constexpr std::size_t kMessageHeaderBytes = 22;  ///< a Message body before its data

/// "Schema", "Chunk", ... (or "opcode 0x42").
std::string opcodeName(std::uint8_t opcode);

/// A record that does not parse; the message says which field and why.
class FormatError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Reads fields from the `n` bytes at `p`. Throws FormatError when a field does not fit.
class ByteCursor {
 public:
  ByteCursor(const std::uint8_t* p, std::size_t n) : p_(p), n_(n) {}
  std::uint8_t u8(const char* what);
  std::uint16_t u16(const char* what);
  std::uint32_t u32(const char* what);
  std::uint64_t u64(const char* what);
  std::string string(const char* what);
  /// Skips a uint32-prefixed byte array (a map, a schema's data).
  void skipPrefixed32(const char* what);
  /// A uint32-prefixed array of fixed-size entries: returns the entry count and leaves the cursor
  /// at the first entry.
  std::size_t array32(std::size_t entry_bytes, const char* what);
  std::size_t position() const { return pos_; }
  std::size_t remaining() const { return n_ - pos_; }

 private:
  const std::uint8_t* take(std::size_t k, const char* what);
  const std::uint8_t* p_;
  std::size_t n_;
  std::size_t pos_ = 0;
};

struct Schema {
  std::uint16_t id = 0;
  std::string name;      ///< the message type, e.g. "sensor_msgs/msg/Imu"
  std::string encoding;  ///< of the schema text, e.g. "ros2msg"
};

struct Channel {
  std::uint16_t id = 0;
  std::uint16_t schema_id = 0;  ///< 0: no schema
  std::string topic;
  std::string message_encoding;  ///< e.g. "cdr"
};

struct MessageHeader {
  std::uint16_t channel = 0;
  std::uint64_t log_time = 0;  ///< [ns]
};

/// A Chunk record's fields before its records, and where those are in the body.
struct ChunkHeader {
  std::uint64_t start = 0, end = 0;  ///< [ns] log times of its first and last messages
  std::uint64_t uncompressed_size = 0;
  std::uint32_t uncompressed_crc = 0;  ///< 0: not computed
  std::string compression;
  std::size_t records_offset = 0;  ///< in the body
  std::uint64_t records_size = 0;  ///< [bytes] compressed
};

struct ChunkIndex {
  std::uint64_t start = 0, end = 0;     ///< [ns]
  std::uint64_t offset = 0;             ///< [bytes] of the Chunk record in the file
  std::uint64_t length = 0;             ///< [bytes] of the whole Chunk record
  std::vector<std::uint16_t> channels;  ///< with messages in the chunk (from its message indexes)
  std::string compression;
};

struct Footer {
  std::uint64_t summary_start = 0;  ///< 0: no summary section
};

struct Statistics {
  std::uint64_t message_start = 0, message_end = 0;  ///< [ns]
  std::uint64_t message_count = 0;
  std::vector<std::pair<std::uint16_t, std::uint64_t>> channel_counts;
};

// Each parses one record body of `n` bytes; throws FormatError.
Schema parseSchema(const std::uint8_t* body, std::size_t n);
Channel parseChannel(const std::uint8_t* body, std::size_t n);
MessageHeader parseMessageHeader(const std::uint8_t* body, std::size_t n);
/// Parses the fixed fields; `n` may be just their prefix of the body as long as it holds them.
ChunkHeader parseChunkHeader(const std::uint8_t* body, std::size_t n);
ChunkIndex parseChunkIndex(const std::uint8_t* body, std::size_t n);
Footer parseFooter(const std::uint8_t* body, std::size_t n);
Statistics parseStatistics(const std::uint8_t* body, std::size_t n);

/// One record in memory.
struct Record {
  std::uint8_t opcode = 0;
  const std::uint8_t* body = nullptr;
  std::size_t length = 0;  ///< [bytes] of the body
  std::size_t offset = 0;  ///< [bytes] of the record in the walked buffer
};

/// Walks the records of a buffer (a chunk's records, a summary section).
class RecordWalker {
 public:
  RecordWalker(const std::uint8_t* p, std::size_t n) : p_(p), n_(n) {}
  /// The next record; false at the end. Throws FormatError "record N at byte B: ..." when a
  /// record does not fit in the buffer.
  bool next(Record& record);
  std::size_t count() const { return count_; }  ///< records returned

 private:
  const std::uint8_t* p_;
  std::size_t n_;
  std::size_t pos_ = 0;
  std::size_t count_ = 0;
};

}  // namespace freeinit::ros2::mcap
