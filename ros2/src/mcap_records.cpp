#include "mcap_records.h"

#include <cstring>

namespace freeinit::ros2::mcap {
namespace {

template <class T>
T littleEndian(const std::uint8_t* p) {
  T v = 0;
  for (std::size_t i = 0; i < sizeof(T); ++i) v |= static_cast<T>(T{p[i]} << (8 * i));
  return v;
}

}  // namespace

std::string opcodeName(std::uint8_t opcode) {
  static constexpr const char* kNames[] = {
      "Header",     "Footer",        "Schema",         "Channel",        "Message",
      "Chunk",      "Message Index", "Chunk Index",    "Attachment",     "Attachment Index",
      "Statistics", "Metadata",      "Metadata Index", "Summary Offset", "Data End"};
  if (opcode >= kHeader && opcode <= kDataEnd) return kNames[opcode - 1];
  const char* digits = "0123456789abcdef";
  return std::string("opcode 0x") + digits[opcode >> 4] + digits[opcode & 15];
}

const std::uint8_t* ByteCursor::take(std::size_t k, const char* what) {
  if (k > remaining())
    throw FormatError(std::string(what) + ": needs " + std::to_string(k) + " bytes at byte " +
                      std::to_string(pos_) + " of a " + std::to_string(n_) + "-byte record");
  const std::uint8_t* q = p_ + pos_;
  pos_ += k;
  return q;
}

std::uint8_t ByteCursor::u8(const char* what) { return *take(1, what); }
std::uint16_t ByteCursor::u16(const char* what) {
  return littleEndian<std::uint16_t>(take(2, what));
}
std::uint32_t ByteCursor::u32(const char* what) {
  return littleEndian<std::uint32_t>(take(4, what));
}
std::uint64_t ByteCursor::u64(const char* what) {
  return littleEndian<std::uint64_t>(take(8, what));
}

std::string ByteCursor::string(const char* what) {
  const std::uint32_t k = u32(what);
  const char* s = reinterpret_cast<const char*>(take(k, what));
  return std::string(s, k);
}

void ByteCursor::skipPrefixed32(const char* what) { take(u32(what), what); }

std::size_t ByteCursor::array32(std::size_t entry_bytes, const char* what) {
  const std::uint32_t k = u32(what);
  if (k > remaining() || k % entry_bytes != 0)
    throw FormatError(std::string(what) + ": " + std::to_string(k) + " bytes of entries of " +
                      std::to_string(entry_bytes) + " bytes, " + std::to_string(remaining()) +
                      " left in the record");
  return k / entry_bytes;
}

Schema parseSchema(const std::uint8_t* body, std::size_t n) {
  ByteCursor c(body, n);
  Schema s;
  s.id = c.u16("Schema id");
  s.name = c.string("Schema name");
  s.encoding = c.string("Schema encoding");
  c.skipPrefixed32("Schema data");
  return s;
}

Channel parseChannel(const std::uint8_t* body, std::size_t n) {
  ByteCursor c(body, n);
  Channel ch;
  ch.id = c.u16("Channel id");
  ch.schema_id = c.u16("Channel schema_id");
  ch.topic = c.string("Channel topic");
  ch.message_encoding = c.string("Channel message_encoding");
  c.skipPrefixed32("Channel metadata");
  return ch;
}

MessageHeader parseMessageHeader(const std::uint8_t* body, std::size_t n) {
  ByteCursor c(body, n);
  MessageHeader m;
  m.channel = c.u16("Message channel_id");
  c.u32("Message sequence");
  m.log_time = c.u64("Message log_time");
  c.u64("Message publish_time");
  return m;
}

ChunkHeader parseChunkHeader(const std::uint8_t* body, std::size_t n) {
  ByteCursor c(body, n);
  ChunkHeader h;
  h.start = c.u64("Chunk message_start_time");
  h.end = c.u64("Chunk message_end_time");
  h.uncompressed_size = c.u64("Chunk uncompressed_size");
  h.uncompressed_crc = c.u32("Chunk uncompressed_crc");
  h.compression = c.string("Chunk compression");
  h.records_size = c.u64("Chunk records");
  h.records_offset = c.position();
  return h;
}

ChunkIndex parseChunkIndex(const std::uint8_t* body, std::size_t n) {
  ByteCursor c(body, n);
  ChunkIndex i;
  i.start = c.u64("Chunk Index message_start_time");
  i.end = c.u64("Chunk Index message_end_time");
  i.offset = c.u64("Chunk Index chunk_start_offset");
  i.length = c.u64("Chunk Index chunk_length");
  const std::size_t entries = c.array32(10, "Chunk Index message_index_offsets");
  for (std::size_t k = 0; k < entries; ++k) {
    i.channels.push_back(c.u16("Chunk Index channel"));
    c.u64("Chunk Index offset");
  }
  c.u64("Chunk Index message_index_length");
  i.compression = c.string("Chunk Index compression");
  c.u64("Chunk Index compressed_size");
  c.u64("Chunk Index uncompressed_size");
  return i;
}

Footer parseFooter(const std::uint8_t* body, std::size_t n) {
  ByteCursor c(body, n);
  Footer f;
  f.summary_start = c.u64("Footer summary_start");
  return f;
}

Statistics parseStatistics(const std::uint8_t* body, std::size_t n) {
  ByteCursor c(body, n);
  Statistics s;
  s.message_count = c.u64("Statistics message_count");
  c.u16("Statistics schema_count");
  c.u32("Statistics channel_count");
  c.u32("Statistics attachment_count");
  c.u32("Statistics metadata_count");
  c.u32("Statistics chunk_count");
  s.message_start = c.u64("Statistics message_start_time");
  s.message_end = c.u64("Statistics message_end_time");
  const std::size_t entries = c.array32(10, "Statistics channel_message_counts");
  for (std::size_t k = 0; k < entries; ++k) {
    const std::uint16_t channel = c.u16("Statistics channel");
    s.channel_counts.emplace_back(channel, c.u64("Statistics count"));
  }
  return s;
}

bool RecordWalker::next(Record& r) {
  if (pos_ == n_) return false;
  if (n_ - pos_ < kRecordHeaderBytes)
    throw FormatError("record " + std::to_string(count_ + 1) + " at byte " + std::to_string(pos_) +
                      ": " + std::to_string(n_ - pos_) + " bytes left, less than a record header");
  const std::uint64_t length = littleEndian<std::uint64_t>(p_ + pos_ + 1);
  if (length > n_ - pos_ - kRecordHeaderBytes)
    throw FormatError("record " + std::to_string(count_ + 1) + " (" + opcodeName(p_[pos_]) +
                      ") at byte " + std::to_string(pos_) + ": a body of " +
                      std::to_string(length) + " bytes, only " +
                      std::to_string(n_ - pos_ - kRecordHeaderBytes) + " left");
  r.opcode = p_[pos_];
  r.body = p_ + pos_ + kRecordHeaderBytes;
  r.length = static_cast<std::size_t>(length);
  r.offset = pos_;
  pos_ += kRecordHeaderBytes + r.length;
  ++count_;
  return true;
}

}  // namespace freeinit::ros2::mcap
