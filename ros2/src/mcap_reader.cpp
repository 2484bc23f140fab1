#include <freeinit/ros2/mcap_reader.h>

#include <algorithm>
#include <cstring>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <queue>
#include <set>
#include <stdexcept>
#include <tuple>
#include <vector>

#include "chunk_decompression.h"
#include "crc32.h"
#include "input_file.h"
#include "mcap_records.h"

namespace freeinit::ros2 {
namespace {

using mcap::FormatError;

constexpr std::size_t kFooterRecordBytes = mcap::kRecordHeaderBytes + mcap::kFooterBodyBytes;

std::int64_t toNs(std::uint64_t t) {
  return t > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max())
             ? std::numeric_limits<std::int64_t>::max()
             : static_cast<std::int64_t>(t);
}

std::uint64_t readU64(const std::uint8_t* p) {
  std::uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}

// A chunk holding messages: where it is, the log times it spans, the channels in it.
struct ChunkRef {
  std::uint64_t offset = 0;  ///< [bytes] of the Chunk record
  std::uint64_t length = 0;  ///< [bytes] of the whole record
  std::uint64_t start = 0, end = 0;
  std::vector<std::uint16_t> channels;  ///< empty: not known
  std::size_t ordinal = 0;              ///< 1-based, in file order
};

// A message of a decompressed chunk waiting its turn: ordered by log time, then file order.
struct Pending {
  std::int64_t log_time;
  std::size_t chunk;   ///< ChunkRef::ordinal
  std::size_t offset;  ///< of the data in the chunk's records
  std::size_t length;
  std::size_t topic;
  bool operator>(const Pending& o) const {
    return std::tie(log_time, chunk, offset) > std::tie(o.log_time, o.chunk, o.offset);
  }
};

struct LoadedChunk {
  std::vector<std::uint8_t> records;
  std::size_t pending = 0;  ///< its messages still in the queue
};

// The next record of a chunk, with the chunk named in any error.
bool nextRecord(mcap::RecordWalker& walker, mcap::Record& r, const std::string& chunk) {
  try {
    return walker.next(r);
  } catch (const FormatError& e) {
    throw FormatError(chunk + ": " + e.what());
  }
}

}  // namespace

struct McapReader::Impl {
  Impl(const std::string& path, const ReaderLimits& l) : file(path), limits(l) {}

  InputFile file;
  ReaderLimits limits;
  std::uint64_t bytes_read = 0;
  std::map<std::uint16_t, mcap::Schema> schemas;
  std::map<std::uint16_t, mcap::Channel> channels;
  std::map<std::uint16_t, std::size_t> channel_topic;  ///< channel id -> topic index
  std::vector<ChunkRef> chunks;                        ///< by (start, offset)
  std::uint64_t data_end = 0;  ///< [bytes] where the data section (or what is whole of it) ends
  bool indexed = false;
  bool top_level_messages = false;  ///< messages outside chunks: read in file order

  // What the Recording shows.
  std::vector<TopicInfo> topics;
  std::optional<TimeRange> range;
  std::vector<std::string> warnings;
  std::map<std::uint16_t, std::uint64_t> counts;                  ///< messages per channel
  std::int64_t first = std::numeric_limits<std::int64_t>::max();  ///< [ns] scan: log times
  std::int64_t last = std::numeric_limits<std::int64_t>::min();

  // Reading.
  ReadOptions options;
  std::vector<bool> wanted;  ///< per topic
  std::size_t next_chunk = 0;
  std::priority_queue<Pending, std::vector<Pending>, std::greater<Pending>> queue;
  std::map<std::size_t, LoadedChunk> loaded;
  std::uint64_t loaded_bytes = 0;  ///< in `loaded`
  std::uint64_t position = 0;      ///< file order: the next top-level record
  std::vector<std::uint8_t> scratch;
  std::vector<std::uint8_t> file_order_chunk;
  std::optional<mcap::RecordWalker> file_order_walker;
  std::string file_order_what;  ///< names the chunk file_order_walker walks

  void read(std::uint64_t offset, std::size_t n, std::vector<std::uint8_t>& out) {
    file.read(offset, n, out);
    bytes_read += n;
  }

  void open();
  bool readSummary();
  void scan();
  /// Registers a Schema or Channel record.
  void define(const mcap::Record& r);
  /// Counts a message of the scan.
  void count(const mcap::MessageHeader& m);
  void makeTopics();
  /// Reads and decompresses the Chunk record at `offset` of `length` bytes (`what` names it).
  mcap::ChunkHeader loadChunk(std::uint64_t offset, std::uint64_t length, const std::string& what,
                              std::vector<std::uint8_t>& records);
  std::size_t topicOf(std::uint16_t channel) const;
  bool inWindow(std::int64_t t) const { return t >= options.start && t <= options.end; }

  void unload(std::size_t ordinal) {
    const auto it = loaded.find(ordinal);
    if (it == loaded.end()) return;
    loaded_bytes -= std::min<std::uint64_t>(loaded_bytes, it->second.records.size());
    loaded.erase(it);
  }

  void start(const ReadOptions& o);
  bool nextInLogOrder(Message& m);
  bool nextInFileOrder(Message& m);
};

void McapReader::Impl::open() {
  const std::uint64_t size = file.size();
  std::vector<std::uint8_t> magic;
  if (size < mcap::kMagicBytes) throw FormatError("a file of " + std::to_string(size) + " bytes");
  read(0, mcap::kMagicBytes, magic);
  if (std::memcmp(magic.data(), mcap::kMagic, mcap::kMagicBytes) != 0)
    throw FormatError("the file does not start with the MCAP magic (\\x89MCAP0\\r\\n)");
  if (!readSummary()) scan();
  makeTopics();
  if (top_level_messages)
    warnings.push_back("messages outside chunks: read in file order, not sorted by log time");
}

// The footer, then the summary section: schemas, channels, statistics, chunk indexes. False when
// there is none to use (the file is then scanned).
bool McapReader::Impl::readSummary() {
  const std::uint64_t size = file.size();
  if (size < 2 * mcap::kMagicBytes + kFooterRecordBytes) return false;
  const std::uint64_t footer_at = size - mcap::kMagicBytes - kFooterRecordBytes;
  std::vector<std::uint8_t> tail;
  read(footer_at, kFooterRecordBytes + mcap::kMagicBytes, tail);
  if (std::memcmp(tail.data() + kFooterRecordBytes, mcap::kMagic, mcap::kMagicBytes) != 0 ||
      tail[0] != mcap::kFooter || readU64(tail.data() + 1) != mcap::kFooterBodyBytes)
    return false;  // not closed: the scan says where it ends
  const mcap::Footer footer =
      mcap::parseFooter(tail.data() + mcap::kRecordHeaderBytes, mcap::kFooterBodyBytes);
  if (footer.summary_start == 0) return false;
  if (footer.summary_start < mcap::kMagicBytes || footer.summary_start > footer_at) {
    warnings.push_back("the footer places the summary at byte " +
                       std::to_string(footer.summary_start) +
                       ", outside the file: the file was scanned instead");
    return false;
  }
  std::vector<std::uint8_t> summary;
  read(footer.summary_start, static_cast<std::size_t>(footer_at - footer.summary_start), summary);
  std::vector<mcap::ChunkIndex> indexes;
  std::optional<mcap::Statistics> stats;
  try {
    mcap::RecordWalker walker(summary.data(), summary.size());
    mcap::Record r;
    while (walker.next(r)) {
      if (r.opcode == mcap::kSchema) {
        const mcap::Schema s = mcap::parseSchema(r.body, r.length);
        schemas[s.id] = s;
      } else if (r.opcode == mcap::kChannel) {
        const mcap::Channel c = mcap::parseChannel(r.body, r.length);
        channels[c.id] = c;
      } else if (r.opcode == mcap::kChunkIndex) {
        indexes.push_back(mcap::parseChunkIndex(r.body, r.length));
      } else if (r.opcode == mcap::kStatistics) {
        stats = mcap::parseStatistics(r.body, r.length);
      }
    }
  } catch (const FormatError& e) {
    warnings.push_back(std::string("the summary section is unreadable (") + e.what() +
                       "): the file was scanned instead");
    schemas.clear();
    channels.clear();
    return false;
  }
  // Without chunk indexes or channels there is nothing to seek with: scan.
  if (indexes.empty() || channels.empty()) {
    schemas.clear();
    channels.clear();
    return false;
  }
  std::sort(
      indexes.begin(), indexes.end(),
      [](const mcap::ChunkIndex& a, const mcap::ChunkIndex& b) { return a.offset < b.offset; });
  for (const mcap::ChunkIndex& i : indexes) {
    const std::size_t ordinal = chunks.size() + 1;
    const std::string what =
        "chunk " + std::to_string(ordinal) + " (at byte " + std::to_string(i.offset) + ")";
    if (i.offset < mcap::kMagicBytes || i.length < mcap::kRecordHeaderBytes ||
        i.length > footer.summary_start || i.offset > footer.summary_start - i.length)
      throw FormatError(what + ": its index gives it " + std::to_string(i.length) +
                        " bytes, which do not fit before the summary at byte " +
                        std::to_string(footer.summary_start));
    if (!isSupportedCompression(i.compression))
      throw FormatError(what + ": compressed with '" + i.compression +
                        "', which is not supported (none, zstd, lz4 are)");
    if (i.start > i.end)
      throw FormatError(what + ": its index has it start at log time " + std::to_string(i.start) +
                        ", after its end " + std::to_string(i.end));
    for (const std::uint16_t c : i.channels)
      if (channels.count(c) == 0)
        throw FormatError(what + ": its index names channel " + std::to_string(c) +
                          ", which the summary lacks");
    chunks.push_back({i.offset, i.length, i.start, i.end, i.channels, ordinal});
  }
  if (stats) {
    for (const auto& [channel, n] : stats->channel_counts) counts[channel] = n;
    if (stats->message_count > 0)
      range = TimeRange{toNs(stats->message_start), toNs(stats->message_end)};
  }
  if (!range) {
    range = TimeRange{std::numeric_limits<std::int64_t>::max(),
                      std::numeric_limits<std::int64_t>::min()};
    for (const ChunkRef& c : chunks) {
      range->first = std::min(range->first, toNs(c.start));
      range->last = std::max(range->last, toNs(c.end));
    }
  }
  data_end = footer.summary_start;
  indexed = true;
  return true;
}

// Walks every record of the data section once: registers schemas and channels, decompresses each
// chunk to learn its channels, times and message counts, and stops where the file stops being
// whole.
void McapReader::Impl::scan() {
  const std::uint64_t size = file.size();
  std::uint64_t pos = mcap::kMagicBytes;
  std::size_t record = 0;
  std::size_t ordinal = 0;
  std::vector<std::uint8_t> head, body, records;
  bool closed = false;
  while (pos < size && !closed) {
    const auto where = [&] {
      return "record " + std::to_string(record) + " at byte " + std::to_string(pos);
    };
    if (size - pos < mcap::kRecordHeaderBytes) {
      warnings.push_back("the file ends at byte " + std::to_string(size) +
                         ", inside the header of record " + std::to_string(record + 1) +
                         " (at byte " + std::to_string(pos) + "): read what is whole");
      break;
    }
    read(pos, mcap::kRecordHeaderBytes, head);
    const std::uint8_t opcode = head[0];
    const std::uint64_t length = readU64(head.data() + 1);
    if (length > size - pos - mcap::kRecordHeaderBytes) {
      warnings.push_back("the file ends at byte " + std::to_string(size) + ", inside record " +
                         std::to_string(record + 1) + " (" + mcap::opcodeName(opcode) +
                         " at byte " + std::to_string(pos) + "): read what is whole");
      break;
    }
    ++record;
    const std::uint64_t body_at = pos + mcap::kRecordHeaderBytes;
    switch (opcode) {
      case mcap::kFooter:
      case mcap::kDataEnd:
        closed = true;
        break;
      case mcap::kSchema:
      case mcap::kChannel:
      case mcap::kMessage:
        read(body_at,
             static_cast<std::size_t>(
                 opcode == mcap::kMessage
                     ? std::min<std::uint64_t>(length, mcap::kMessageHeaderBytes)
                     : length),
             body);
        try {
          if (opcode == mcap::kMessage)
            count(mcap::parseMessageHeader(body.data(), body.size()));
          else
            define({opcode, body.data(), body.size(), 0});
        } catch (const FormatError& e) {
          throw FormatError(where() + ": " + e.what());
        }
        top_level_messages = top_level_messages || opcode == mcap::kMessage;
        break;
      case mcap::kChunk: {
        ++ordinal;
        const std::string what = "chunk " + std::to_string(ordinal) + " (" + where() + ")";
        loadChunk(pos, mcap::kRecordHeaderBytes + length, what, records);
        ChunkRef ref{pos,
                     mcap::kRecordHeaderBytes + length,
                     std::numeric_limits<std::uint64_t>::max(),
                     0,
                     {},
                     ordinal};
        std::set<std::uint16_t> in_chunk;
        mcap::RecordWalker walker(records.data(), records.size());
        mcap::Record r;
        while (nextRecord(walker, r, what)) {
          try {
            if (r.opcode == mcap::kSchema || r.opcode == mcap::kChannel) {
              define(r);
            } else if (r.opcode == mcap::kMessage) {
              const mcap::MessageHeader m = mcap::parseMessageHeader(r.body, r.length);
              count(m);
              ref.start = std::min(ref.start, m.log_time);
              ref.end = std::max(ref.end, m.log_time);
              in_chunk.insert(m.channel);
            }
          } catch (const FormatError& e) {
            throw FormatError(what + ", record " + std::to_string(walker.count()) + ": " +
                              e.what());
          }
        }
        ref.channels.assign(in_chunk.begin(), in_chunk.end());
        if (!ref.channels.empty()) chunks.push_back(ref);
        break;
      }
      default:
        break;  // indexes, attachments, metadata: not needed
    }
    pos = body_at + length;
  }
  if (!closed && pos == size)
    warnings.push_back("the file ends at byte " + std::to_string(size) + " after record " +
                       std::to_string(record) +
                       ", without the end of its data section: read what is whole");
  data_end = pos;
  if (first <= last) range = TimeRange{first, last};
}

void McapReader::Impl::define(const mcap::Record& r) {
  if (r.opcode == mcap::kSchema) {
    const mcap::Schema s = mcap::parseSchema(r.body, r.length);
    schemas[s.id] = s;
  } else {
    const mcap::Channel c = mcap::parseChannel(r.body, r.length);
    channels[c.id] = c;
  }
}

void McapReader::Impl::count(const mcap::MessageHeader& m) {
  if (channels.count(m.channel) == 0)
    throw FormatError("a message on channel " + std::to_string(m.channel) +
                      ", which no Channel record before it declares");
  ++counts[m.channel];
  first = std::min(first, toNs(m.log_time));
  last = std::max(last, toNs(m.log_time));
}

void McapReader::Impl::makeTopics() {
  std::map<std::tuple<std::string, std::string, std::string>, std::size_t> index;
  for (const auto& [id, c] : channels) {
    const auto schema = schemas.find(c.schema_id);
    const std::string type = schema == schemas.end() ? std::string() : schema->second.name;
    const auto [it, added] =
        index.emplace(std::tuple(c.topic, type, c.message_encoding), topics.size());
    if (added) topics.push_back({c.topic, type, c.message_encoding, std::nullopt});
    channel_topic[id] = it->second;
  }
  // Counts where the file gives them: the statistics of an indexed file, the scan's otherwise.
  if (!indexed || !counts.empty()) {
    for (TopicInfo& t : topics) t.message_count = 0;
    for (const auto& [channel, n] : counts) {
      const auto it = channel_topic.find(channel);
      if (it != channel_topic.end()) *topics[it->second].message_count += n;
    }
  }
  std::sort(chunks.begin(), chunks.end(), [](const ChunkRef& a, const ChunkRef& b) {
    return std::tie(a.start, a.offset) < std::tie(b.start, b.offset);
  });
}

mcap::ChunkHeader McapReader::Impl::loadChunk(std::uint64_t offset, std::uint64_t length,
                                              const std::string& what,
                                              std::vector<std::uint8_t>& records) {
  std::vector<std::uint8_t> head;
  read(offset, mcap::kRecordHeaderBytes, head);
  const std::uint64_t body_length = readU64(head.data() + 1);
  if (head[0] != mcap::kChunk || mcap::kRecordHeaderBytes + body_length != length)
    throw FormatError(what + ": expected a Chunk record of " + std::to_string(length) +
                      " bytes at byte " + std::to_string(offset) + ", found " +
                      mcap::opcodeName(head[0]) + " of " + std::to_string(body_length));
  if (body_length > limits.max_chunk_bytes)
    throw FormatError(what + ": " + std::to_string(body_length) + " bytes, more than the " +
                      std::to_string(limits.max_chunk_bytes) +
                      " accepted (ReaderLimits::max_chunk_bytes)");
  read(offset + mcap::kRecordHeaderBytes, static_cast<std::size_t>(body_length), scratch);
  mcap::ChunkHeader h;
  try {
    h = mcap::parseChunkHeader(scratch.data(), scratch.size());
  } catch (const FormatError& e) {
    throw FormatError(what + ": " + e.what());
  }
  if (h.records_size != scratch.size() - h.records_offset)
    throw FormatError(what + ": records of " + std::to_string(h.records_size) +
                      " bytes in a body of " + std::to_string(body_length) + " with " +
                      std::to_string(h.records_offset) + " bytes of header");
  if (!isSupportedCompression(h.compression))
    throw FormatError(what + ": compressed with '" + h.compression +
                      "', which is not supported (none, zstd, lz4 are)");
  if (h.uncompressed_size > limits.max_chunk_bytes)
    throw FormatError(what + ": decompresses to " + std::to_string(h.uncompressed_size) +
                      " bytes, more than the " + std::to_string(limits.max_chunk_bytes) +
                      " accepted (ReaderLimits::max_chunk_bytes)");
  try {
    decompressChunk(h.compression, scratch.data() + h.records_offset,
                    static_cast<std::size_t>(h.records_size), h.uncompressed_size, records);
  } catch (const std::runtime_error& e) {
    throw FormatError(what + ": " + e.what());
  }
  if (limits.verify_crc && h.uncompressed_crc != 0 &&
      crc32(records.data(), records.size()) != h.uncompressed_crc)
    throw FormatError(what + ": its records do not match their CRC (a corrupt file)");
  return h;
}

std::size_t McapReader::Impl::topicOf(std::uint16_t channel) const {
  const auto it = channel_topic.find(channel);
  if (it == channel_topic.end())
    throw FormatError("a message on channel " + std::to_string(channel) +
                      ", which the file does not declare");
  return it->second;
}

void McapReader::Impl::start(const ReadOptions& o) {
  options = o;
  wanted.assign(topics.size(), o.topics.empty());
  for (const std::size_t t : o.topics) wanted[t] = true;
  next_chunk = 0;
  queue = {};
  loaded.clear();
  loaded_bytes = 0;
  position = mcap::kMagicBytes;
  file_order_walker.reset();
}

// Log-time order: a chunk is loaded once the earliest waiting message is not earlier than the
// chunk's first log time, so no message of a later-loaded chunk can precede one already returned.
bool McapReader::Impl::nextInLogOrder(Message& m) {
  while (next_chunk < chunks.size() &&
         (queue.empty() || toNs(chunks[next_chunk].start) <= queue.top().log_time)) {
    const ChunkRef& c = chunks[next_chunk++];
    if (toNs(c.start) > options.end) {
      next_chunk = chunks.size();  // sorted by start: none later overlaps the window
      break;
    }
    if (toNs(c.end) < options.start) continue;
    if (!c.channels.empty() &&
        std::none_of(c.channels.begin(), c.channels.end(), [&](std::uint16_t ch) {
          const auto it = channel_topic.find(ch);
          return it != channel_topic.end() && wanted[it->second];
        }))
      continue;
    const std::string what =
        "chunk " + std::to_string(c.ordinal) + " (at byte " + std::to_string(c.offset) + ")";
    LoadedChunk& chunk = loaded[c.ordinal];
    try {
      loadChunk(c.offset, c.length, what, chunk.records);
      loaded_bytes += chunk.records.size();
      if (loaded_bytes > limits.max_loaded_bytes)
        throw FormatError(what + ": with the chunks overlapping it in time, more than " +
                          std::to_string(limits.max_loaded_bytes) +
                          " bytes at once (ReaderLimits::max_loaded_bytes): the file's chunks are "
                          "far from log-time order");
      mcap::RecordWalker walker(chunk.records.data(), chunk.records.size());
      mcap::Record r;
      while (nextRecord(walker, r, what)) {
        if (r.opcode != mcap::kMessage) continue;
        mcap::MessageHeader h;
        std::size_t topic = 0;
        try {
          h = mcap::parseMessageHeader(r.body, r.length);
          if (h.log_time < c.start || h.log_time > c.end)
            throw FormatError("log time " + std::to_string(h.log_time) +
                              " outside the chunk's declared span [" + std::to_string(c.start) +
                              ", " + std::to_string(c.end) + "]");
          topic = topicOf(h.channel);
        } catch (const FormatError& e) {
          throw FormatError(what + ", record " + std::to_string(walker.count()) + ": " + e.what());
        }
        if (!wanted[topic] || !inWindow(toNs(h.log_time))) continue;
        queue.push(
            {toNs(h.log_time), c.ordinal,
             static_cast<std::size_t>(r.body - chunk.records.data()) + mcap::kMessageHeaderBytes,
             r.length - mcap::kMessageHeaderBytes, topic});
        ++chunk.pending;
      }
    } catch (const FormatError&) {
      unload(c.ordinal);
      throw;
    }
    if (chunk.pending == 0) unload(c.ordinal);
  }
  if (queue.empty()) return false;
  const Pending p = queue.top();
  queue.pop();
  LoadedChunk& chunk = loaded.at(p.chunk);
  m.topic = p.topic;
  m.log_time = p.log_time;
  m.data.assign(chunk.records.begin() + static_cast<std::ptrdiff_t>(p.offset),
                chunk.records.begin() + static_cast<std::ptrdiff_t>(p.offset + p.length));
  if (--chunk.pending == 0) unload(p.chunk);
  return true;
}

// File order (messages outside chunks): record after record, chunks decompressed as met.
bool McapReader::Impl::nextInFileOrder(Message& m) {
  std::vector<std::uint8_t> head;
  for (;;) {
    if (file_order_walker) {
      mcap::Record r;
      while (nextRecord(*file_order_walker, r, file_order_what)) {
        if (r.opcode != mcap::kMessage) continue;
        mcap::MessageHeader h;
        std::size_t topic = 0;
        try {
          h = mcap::parseMessageHeader(r.body, r.length);
          topic = topicOf(h.channel);
        } catch (const FormatError& e) {
          throw FormatError(file_order_what + ", record " +
                            std::to_string(file_order_walker->count()) + ": " + e.what());
        }
        if (!wanted[topic] || !inWindow(toNs(h.log_time))) continue;
        m.topic = topic;
        m.log_time = toNs(h.log_time);
        m.data.assign(r.body + mcap::kMessageHeaderBytes, r.body + r.length);
        return true;
      }
      file_order_walker.reset();
    }
    if (position >= data_end) return false;
    read(position, mcap::kRecordHeaderBytes, head);
    const std::uint64_t length = readU64(head.data() + 1);
    const std::uint64_t at = position;
    position += mcap::kRecordHeaderBytes + length;  // within data_end: the scan checked it
    if (head[0] == mcap::kChunk) {
      file_order_what = "the chunk at byte " + std::to_string(at);
      loadChunk(at, mcap::kRecordHeaderBytes + length, file_order_what, file_order_chunk);
      file_order_walker.emplace(file_order_chunk.data(), file_order_chunk.size());
    } else if (head[0] == mcap::kMessage) {
      read(at + mcap::kRecordHeaderBytes, static_cast<std::size_t>(length), scratch);
      mcap::MessageHeader h;
      std::size_t topic = 0;
      try {
        h = mcap::parseMessageHeader(scratch.data(), scratch.size());
        topic = topicOf(h.channel);
      } catch (const FormatError& e) {
        throw FormatError("the message at byte " + std::to_string(at) + ": " + e.what());
      }
      if (!wanted[topic] || !inWindow(toNs(h.log_time))) continue;
      m.topic = topic;
      m.log_time = toNs(h.log_time);
      m.data.assign(scratch.begin() + mcap::kMessageHeaderBytes, scratch.end());
      return true;
    }
  }
}

McapReader::McapReader(const std::string& path, const ReaderLimits& limits)
    : Recording(path, "an MCAP file (ROS 2)") {
  try {
    impl_ = std::make_unique<Impl>(path, limits);
  } catch (const std::exception& e) {
    throw RecordingError(path + ": " + e.what());
  }
  try {
    impl_->open();
  } catch (const std::exception& e) {
    throw error(e.what());
  }
  topics_ = impl_->topics;
  time_range_ = impl_->range;
  warnings_ = impl_->warnings;
  ordered_ = !impl_->top_level_messages;
  impl_->start({});
}

McapReader::~McapReader() = default;

void McapReader::start(const ReadOptions& options) {
  checkOptions(options);
  impl_->start(options);
}

bool McapReader::next(Message& message) {
  try {
    return impl_->top_level_messages ? impl_->nextInFileOrder(message)
                                     : impl_->nextInLogOrder(message);
  } catch (const std::exception& e) {
    throw error(e.what());
  }
}

bool McapReader::indexed() const { return impl_->indexed; }
std::size_t McapReader::chunkCount() const { return impl_->chunks.size(); }
std::uint64_t McapReader::bytesRead() const { return impl_->bytes_read; }

}  // namespace freeinit::ros2
