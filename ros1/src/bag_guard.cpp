// The ROS bag v2.0 format (http://wiki.ros.org/Bags/Format/2.0): after the line "#ROSBAG V2.0\n",
// a sequence of records, each
//   u32 header_len, header (fields: u32 field_len, "name=value"), u32 data_len, data.
// op 0x03 file header (index_pos, conn_count, chunk_count), then chunks (op 0x05: compression,
// size; data = message (0x02) and connection (0x07) records) each followed by its index records
// (op 0x04: ver, conn, count; data = count x {u32 sec, u32 nsec, u32 offset in the chunk}), and at
// index_pos conn_count connection records (op 0x07; data = the connection header, in header
// format) and chunk_count chunk-info records (op 0x06: ver, chunk_pos, start/end time, count;
// data = count x {u32 conn, u32 messages}). All integers little-endian.
#include <bzlib.h>
#include <fcntl.h>
#include <freeinit/ros1/bag_guard.h>
#include <lz4.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <map>
#include <memory>
#include <set>
#include <stdexcept>
#include <vector>

namespace freeinit::ros1 {
namespace {

constexpr std::uint8_t kOpMessage = 0x02, kOpFileHeader = 0x03, kOpIndex = 0x04, kOpChunk = 0x05,
                       kOpChunkInfo = 0x06, kOpConnection = 0x07;
constexpr char kVersionLine[] = "#ROSBAG V2.0\n";
constexpr std::size_t kVersionLineBytes = sizeof(kVersionLine) - 1;

std::string opName(std::uint8_t op) {
  switch (op) {
    case kOpMessage:
      return "message record";
    case kOpFileHeader:
      return "file header record";
    case kOpIndex:
      return "index record";
    case kOpChunk:
      return "chunk record";
    case kOpChunkInfo:
      return "chunk info record";
    case kOpConnection:
      return "connection record";
  }
  return "record of op " + std::to_string(op);
}

std::uint32_t u32At(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) | static_cast<std::uint32_t>(p[1]) << 8 |
         static_cast<std::uint32_t>(p[2]) << 16 | static_cast<std::uint32_t>(p[3]) << 24;
}

// A failed check: what is wrong where; the caller adds the file and the offset.
struct Bad : std::runtime_error {
  Bad(std::uint64_t at, const std::string& what) : std::runtime_error(what), offset(at) {}
  std::uint64_t offset;
};

// The fields of one header, as ros::Header::parse would read them, after checking what it does
// not: each field's 4-byte length and its bytes lie within the header, and the field has a '='.
using Fields = std::map<std::string, std::string>;

Fields parseFields(const std::uint8_t* p, std::uint64_t n, std::uint64_t at, const char* what) {
  Fields f;
  std::uint64_t pos = 0;
  while (pos < n) {
    if (n - pos < 4)
      throw Bad(at + pos, std::string(what) + ": " + std::to_string(n - pos) +
                              " byte(s) left at its end, too few for a field length");
    const std::uint32_t len = u32At(p + pos);
    pos += 4;
    if (len > n - pos)
      throw Bad(at + pos - 4, std::string(what) + ": a field of " + std::to_string(len) +
                                  " bytes, but only " + std::to_string(n - pos) +
                                  " are left in the header");
    const char* s = reinterpret_cast<const char*>(p + pos);
    const char* eq = static_cast<const char*>(std::memchr(s, '=', len));
    if (eq == nullptr || eq == s)
      throw Bad(at + pos - 4, std::string(what) + ": a field without a 'name='");
    f.emplace(std::string(s, eq), std::string(eq + 1, s + len));
    pos += len;
  }
  return f;
}

// A header field of a fixed binary size (librosbag's readField checks the size the same way).
template <class T>
T fixedField(const Fields& f, const char* name, std::uint64_t at, const std::string& what) {
  const auto it = f.find(name);
  if (it == f.end()) throw Bad(at, what + ": no '" + name + "' field");
  if (it->second.size() != sizeof(T))
    throw Bad(at, what + ": field '" + name + "' has " + std::to_string(it->second.size()) +
                      " bytes, expected " + std::to_string(sizeof(T)));
  T v;
  std::memcpy(&v, it->second.data(), sizeof(T));
  return v;
}

const std::string& stringField(const Fields& f, const char* name, std::uint64_t at,
                               const std::string& what) {
  const auto it = f.find(name);
  if (it == f.end() || it->second.empty()) throw Bad(at, what + ": no '" + name + "' field");
  return it->second;
}

// Random access to a byte range: the file, or a decompressed chunk in memory.
class Bytes {
 public:
  virtual ~Bytes() = default;
  virtual std::uint64_t size() const = 0;
  /// Copies [at, at + n); the caller has checked that it lies within size().
  virtual void read(std::uint64_t at, std::uint8_t* dst, std::size_t n) = 0;
};

// The file, read with pread: exactly the bytes asked for (a buffered stream would read a buffer's
// worth at every seek, most of a small chunk).
class FileBytes : public Bytes {
 public:
  explicit FileBytes(const std::string& path) : fd_(::open(path.c_str(), O_RDONLY | O_CLOEXEC)) {
    struct stat st {};
    if (fd_ < 0 || ::fstat(fd_, &st) != 0 || !S_ISREG(st.st_mode)) {
      if (fd_ >= 0) ::close(fd_);
      throw std::runtime_error("cannot open");
    }
    size_ = static_cast<std::uint64_t>(st.st_size);
  }
  ~FileBytes() override { ::close(fd_); }
  FileBytes(const FileBytes&) = delete;
  FileBytes& operator=(const FileBytes&) = delete;
  std::uint64_t size() const override { return size_; }
  void read(std::uint64_t at, std::uint8_t* dst, std::size_t n) override {
    std::size_t done = 0;
    while (done < n) {
      const ::ssize_t k = ::pread(fd_, dst + done, n - done, static_cast<::off_t>(at + done));
      if (k < 0 && errno == EINTR) continue;
      if (k <= 0) throw Bad(at + done, "read error");
      done += static_cast<std::size_t>(k);
    }
    bytes_read_ += n;
  }
  std::uint64_t bytesRead() const { return bytes_read_; }

 private:
  int fd_ = -1;
  std::uint64_t size_ = 0;
  std::uint64_t bytes_read_ = 0;
};

class MemoryBytes : public Bytes {
 public:
  explicit MemoryBytes(const std::vector<std::uint8_t>& b) : b_(b) {}
  std::uint64_t size() const override { return b_.size(); }
  void read(std::uint64_t at, std::uint8_t* dst, std::size_t n) override {
    if (n > 0) std::memcpy(dst, b_.data() + at, n);
  }

 private:
  const std::vector<std::uint8_t>& b_;
};

// One record's framing, checked against [begin, end) of its container.
struct Record {
  std::uint64_t at = 0;  // offset of header_len
  Fields header;
  std::uint8_t op = 0;
  std::uint64_t data_at = 0;
  std::uint32_t data_len = 0;
  std::uint64_t next() const { return data_at + data_len; }
};

// `in_chunk`: the bytes are a chunk's data (for the message), else the file.
Record readRecord(Bytes& b, std::uint64_t at, std::uint64_t end, const char* where,
                  bool in_chunk = false) {
  Record r;
  r.at = at;
  auto need = [&](std::uint64_t from, std::uint64_t n, const std::string& what) {
    if (n > end - from)
      throw Bad(from, std::string(where) + ": " + what + " of " + std::to_string(n) +
                          " bytes, but only " + std::to_string(end - from) + " are left" +
                          (in_chunk ? " in the chunk" : " in the file (truncated bag?)"));
  };
  std::array<std::uint8_t, 4> len{};
  need(at, 4, "a record header length");
  b.read(at, len.data(), 4);
  const std::uint32_t header_len = u32At(len.data());
  need(at + 4, header_len, "a record header");
  std::vector<std::uint8_t> header(header_len);
  b.read(at + 4, header.data(), header_len);
  r.header = parseFields(header.data(), header_len, at + 4, "record header");
  r.op = fixedField<std::uint8_t>(r.header, "op", at, "record header");
  const std::uint64_t data_len_at = at + 4 + header_len;
  need(data_len_at, 4, "a record data length");
  b.read(data_len_at, len.data(), 4);
  r.data_len = u32At(len.data());
  r.data_at = data_len_at + 4;
  need(r.data_at, r.data_len, opName(r.op) + " data");
  return r;
}

std::vector<std::uint8_t> readData(Bytes& b, const Record& r) {
  std::vector<std::uint8_t> d(r.data_len);
  b.read(r.data_at, d.data(), d.size());
  return d;
}

// What the last chunk holds (its records by offset in the uncompressed data), kept until the next
// chunk: its index records follow it. Only one chunk's records are held at a time.
struct Chunk {
  std::uint64_t at = 0;
  std::map<std::uint32_t, std::uint8_t> records;  // offset -> op
};

// Decompresses a bz2 chunk, producing at most `declared` bytes (growing as output appears, so
// that a corrupt size field is never allocated).
std::vector<std::uint8_t> bz2Decompress(const std::vector<std::uint8_t>& in, std::uint32_t declared,
                                        std::uint64_t at) {
  bz_stream s{};
  if (BZ2_bzDecompressInit(&s, 0, 0) != BZ_OK) throw Bad(at, "bz2: cannot initialize");
  std::vector<std::uint8_t> out(std::min<std::uint64_t>(declared, 4 * in.size() + 65536));
  s.next_in = const_cast<char*>(reinterpret_cast<const char*>(in.data()));
  s.avail_in = static_cast<unsigned>(in.size());
  std::uint64_t produced = 0;
  int ret = BZ_OK;
  while (true) {
    if (produced == out.size()) {
      if (out.size() == declared) break;  // full: any more output is too much (checked below)
      out.resize(std::min<std::uint64_t>(declared, 2 * out.size()));
    }
    s.next_out = reinterpret_cast<char*>(out.data() + produced);
    s.avail_out = static_cast<unsigned>(out.size() - produced);
    ret = BZ2_bzDecompress(&s);
    produced = out.size() - s.avail_out;
    if (ret != BZ_OK) break;
    if (s.avail_in == 0 && s.avail_out > 0) break;  // input used up without an end of stream
  }
  // Full output but not at the end of the stream: one more byte would exceed the declared size.
  if (ret == BZ_OK && produced == declared) {
    char extra;
    s.next_out = &extra;
    s.avail_out = 1;
    ret = BZ2_bzDecompress(&s);
    if (s.avail_out == 0) {
      BZ2_bzDecompressEnd(&s);
      throw Bad(
          at, "bz2 chunk decompresses to more than its declared size " + std::to_string(declared));
    }
  }
  BZ2_bzDecompressEnd(&s);
  if (ret != BZ_STREAM_END)
    throw Bad(at, "bz2 chunk data are corrupt or truncated (bzip2 error " + std::to_string(ret) +
                      " after " + std::to_string(produced) + " bytes)");
  out.resize(produced);
  return out;
}

// Decompresses an lz4 chunk in the frame layout roslz4 reads, with the checks roslz4 lacks (it
// copies a block of the size the stream declares into a buffer of the frame's block size).
std::vector<std::uint8_t> lz4Decompress(const std::vector<std::uint8_t>& in, std::uint32_t declared,
                                        std::uint64_t at) {
  auto bad = [&](const std::string& what) { return Bad(at, "lz4 chunk: " + what); };
  if (in.size() < 7 || u32At(in.data()) != 0x184D2204) throw bad("no lz4 frame header");
  const std::uint8_t flg = in[4], bd = in[5];
  // version 01, independent blocks, no block checksum, no content size, content checksum, no
  // dictionary, reserved bits 0: the only frame roslz4 accepts.
  if (flg != 0x64 || (bd & 0x8F) != 0 || ((bd >> 4) & 7) < 4)
    throw bad("frame flags " + std::to_string(flg) + "/" + std::to_string(bd) +
              " are not those of a rosbag lz4 chunk");
  const std::size_t max_block = std::size_t{1} << (8 + 2 * ((bd >> 4) & 7));  // 64 KB .. 4 MB
  std::vector<std::uint8_t> out;
  std::size_t pos = 7;
  while (true) {
    if (in.size() - pos < 4) throw bad("truncated (no end mark)");
    const std::uint32_t word = u32At(in.data() + pos);
    pos += 4;
    if (word == 0) break;
    const bool stored = (word & 0x80000000U) != 0;
    const std::size_t size = word & 0x7FFFFFFFU;
    if (size > max_block)
      throw bad("a block of " + std::to_string(size) + " bytes in a frame of " +
                std::to_string(max_block) + "-byte blocks");
    if (size > in.size() - pos) throw bad("truncated block");
    const std::size_t room = declared - out.size();
    if (stored) {
      if (size > room) throw bad("decompresses to more than its declared size");
      out.insert(out.end(), in.begin() + static_cast<std::ptrdiff_t>(pos),
                 in.begin() + static_cast<std::ptrdiff_t>(pos + size));
    } else {
      const std::size_t before = out.size();
      out.resize(before + std::min(room, max_block));
      const int n =
          LZ4_decompress_safe(reinterpret_cast<const char*>(in.data() + pos),
                              reinterpret_cast<char*>(out.data() + before), static_cast<int>(size),
                              static_cast<int>(out.size() - before));
      if (n < 0) throw bad("corrupt block (or larger than the declared size)");
      out.resize(before + static_cast<std::size_t>(n));
    }
    pos += size;
  }
  if (in.size() - pos < 4) throw bad("truncated (no content checksum)");
  return out;
}

class Checker {
 public:
  Checker(Bytes& file, const BagGuardLimits& limits) : file_(file), limits_(limits) {}

  void run() {
    const std::uint64_t size = file_.size();
    versionLine();
    std::uint64_t at = kVersionLineBytes;
    std::vector<std::pair<std::uint64_t, std::uint8_t>> top;  // (offset, op) of every record
    while (at < size) {
      const Record r = readRecord(file_, at, size, "record");
      top.emplace_back(at, r.op);
      if (top.size() == 1 && r.op != kOpFileHeader)
        throw Bad(at, "the first record is a " + opName(r.op) + ", not the file header");
      switch (r.op) {
        case kOpFileHeader:
          if (top.size() != 1) throw Bad(at, "a second file header record");
          fileHeader(r);
          break;
        case kOpChunk:
          chunk(r);
          break;
        case kOpIndex:
          index(r);
          break;
        case kOpConnection:
          connection(r, file_);
          break;
        case kOpChunkInfo:
          chunkInfo(r);
          break;
        default:
          throw Bad(at, "a " + opName(r.op) + ", which a bag v2.0 does not have");
      }
      at = r.next();
    }
    finish(top);
  }

  // What librosbag reads when it opens a bag, and nothing else: the version line, the file header,
  // the connection and chunk info records at index_pos, and for every chunk its record header and
  // the index records after its data. The chunks' data are not read.
  void readIndex(BagIndex& out) {
    const std::uint64_t size = file_.size();
    versionLine();
    const Record h = readRecord(file_, kVersionLineBytes, size, "record");
    if (h.op != kOpFileHeader)
      throw Bad(h.at, "the first record is a " + opName(h.op) + ", not the file header");
    fileHeader(h);
    if (conn_count_ == 0 && chunk_count_ == 0) return;  // a bag closed without a message
    if (index_pos_ < h.next() || index_pos_ >= size)
      throw Bad(h.at, "the file header's index position " + std::to_string(index_pos_) +
                          " is not within the file's " + std::to_string(size) +
                          " bytes (truncated bag?)");
    std::uint64_t at = index_pos_;
    for (std::uint32_t k = 0; k < conn_count_; ++k) {
      const Record r = readRecord(file_, at, size, "connection record");
      if (r.op != kOpConnection)
        throw Bad(at, "a " + opName(r.op) + " where the index has a connection record");
      connection(r, file_);
      out.topics[fixedField<std::uint32_t>(r.header, "conn", at, "connection record")] =
          r.header.at("topic");
      at = r.next();
    }
    for (std::uint32_t k = 0; k < chunk_count_; ++k) {
      const Record r = readRecord(file_, at, size, "chunk info record");
      if (r.op != kOpChunkInfo)
        throw Bad(at, "a " + opName(r.op) + " where the index has a chunk info record");
      chunkInfo(r);
      at = r.next();
    }
    for (const Info& info : infos_) {
      BagIndex::Chunk c;
      c.pos = info.chunk_pos;
      const Record r = readRecord(file_, c.pos, size, "chunk record");
      if (r.op != kOpChunk)
        throw Bad(info.at, "chunk info points at byte " + std::to_string(c.pos) + ", a " +
                               opName(r.op) + ", not a chunk record");
      chunkHeader(r);
      std::uint64_t next = r.next();
      for (std::size_t i = 0; i < info.connections; ++i) {
        const Record x = readRecord(file_, next, size, "index record");
        if (x.op != kOpIndex)
          throw Bad(next, "a " + opName(x.op) + " where chunk info at byte " +
                              std::to_string(info.at) + " announces " +
                              std::to_string(info.connections) + " index records");
        const IndexEntries e = indexEntries(x);
        if (out.topics.count(e.conn) == 0)
          throw Bad(x.at, "connection " + std::to_string(e.conn) +
                              " is used but not among the index's connection records");
        auto& span = c.connections[e.conn];
        for (std::uint32_t j = 0; j < e.count; ++j) {
          const std::uint64_t t = std::uint64_t{u32At(e.data.data() + 12 * j)} * 1000000000U +
                                  u32At(e.data.data() + 12 * j + 4);
          span.first = span.messages == 0 ? t : std::min(span.first, t);
          span.last = span.messages == 0 ? t : std::max(span.last, t);
          ++span.messages;
        }
        next = x.next();
      }
      c.bytes = next - c.pos;
      c.index_records = info.connections;
      out.chunks.push_back(std::move(c));
    }
  }

  // The data of one chunk of the index (chunk record at `pos`, followed by `index_records`
  // index records), checked as run() checks every chunk: decompressed within its declared size,
  // its records walked, its index entries pointing at message records of known connections.
  void checkChunk(std::uint64_t pos, std::size_t index_records,
                  const std::map<std::uint32_t, std::string>& topics) {
    const std::uint64_t size = file_.size();
    const Record r = readRecord(file_, pos, size, "chunk record");
    if (r.op != kOpChunk) throw Bad(pos, "a " + opName(r.op) + ", not a chunk record");
    referenced_.clear();
    chunk(r);
    std::uint64_t at = r.next();
    for (std::size_t i = 0; i < index_records; ++i) {
      const Record x = readRecord(file_, at, size, "index record");
      if (x.op != kOpIndex) throw Bad(at, "a " + opName(x.op) + " where an index record was");
      index(x);
      at = x.next();
    }
    for (const auto& [conn, where] : referenced_)
      if (topics.count(conn) == 0)
        throw Bad(where, "connection " + std::to_string(conn) +
                             " is used but not among the index's connection records");
  }

 private:
  void versionLine() {
    const std::uint64_t size = file_.size();
    std::array<std::uint8_t, kVersionLineBytes> line{};
    if (size < kVersionLineBytes)
      throw Bad(0, "only " + std::to_string(size) + " bytes: not a ROS bag");
    file_.read(0, line.data(), line.size());
    if (std::memcmp(line.data(), kVersionLine, kVersionLineBytes) != 0) {
      if (std::memcmp(line.data(), "#ROSBAG V1.2", 12) == 0)
        throw Bad(0, "a ROS bag of format 1.2: only 2.0 is read (convert it with `rosbag fix`)");
      throw Bad(0, "does not start with \"#ROSBAG V2.0\": not a ROS bag (v2.0)");
    }
  }

  void fileHeader(const Record& r) {
    const char* w = "file header record";
    index_pos_ = fixedField<std::uint64_t>(r.header, "index_pos", r.at, w);
    conn_count_ = fixedField<std::uint32_t>(r.header, "conn_count", r.at, w);
    chunk_count_ = fixedField<std::uint32_t>(r.header, "chunk_count", r.at, w);
    const auto enc = r.header.find("encryptor");
    if (enc != r.header.end() && !enc->second.empty() && enc->second != "rosbag/NoEncryptor")
      throw Bad(r.at, "an encrypted bag (" + enc->second + "): decrypt it first (rosbag decrypt)");
    if (index_pos_ == 0)
      throw Bad(r.at,
                "the bag is not indexed (a recording that did not finish?): run "
                "`rosbag reindex` on it");
  }

  // The chunk record's header fields: compression and declared size (what librosbag reads of a
  // chunk when it opens the bag).
  std::pair<std::string, std::uint32_t> chunkHeader(const Record& r) {
    const char* w = "chunk record";
    const std::string& compression = stringField(r.header, "compression", r.at, w);
    const std::uint32_t declared = fixedField<std::uint32_t>(r.header, "size", r.at, w);
    if (declared > limits_.max_chunk_bytes)
      throw Bad(r.at, "chunk of " + std::to_string(declared) + " bytes, more than the " +
                          std::to_string(limits_.max_chunk_bytes) + " accepted");
    if (compression != "none" && compression != "bz2" && compression != "lz4")
      throw Bad(r.at, "chunk compression '" + compression + "' (none, bz2 or lz4 are read)");
    if (compression == "none" && declared != r.data_len)
      throw Bad(r.at, "uncompressed chunk of size " + std::to_string(declared) + " holds " +
                          std::to_string(r.data_len) + " bytes");
    return {compression, declared};
  }

  void chunk(const Record& r) {
    const auto [compression, declared] = chunkHeader(r);
    Chunk& c = chunk_;
    c.at = r.at;
    c.records.clear();
    std::vector<std::uint8_t> data;
    if (compression == "none") {
      data = readData(file_, r);
    } else {
      const std::vector<std::uint8_t> packed = readData(file_, r);
      data = compression == "bz2" ? bz2Decompress(packed, declared, r.data_at)
                                  : lz4Decompress(packed, declared, r.data_at);
      if (data.size() != declared)
        throw Bad(r.at, compression + " chunk of declared size " + std::to_string(declared) +
                            " decompresses to " + std::to_string(data.size()) + " bytes");
    }
    walkChunk(data, c);
    index_records_[r.at] = 0;
    have_chunk_ = true;
  }

  // The records inside a chunk; offsets are relative to the chunk's uncompressed data. Errors
  // name the chunk's offset in the file and the record's in the chunk.
  void walkChunk(const std::vector<std::uint8_t>& data, Chunk& c) {
    MemoryBytes b(data);
    std::uint64_t at = 0;
    try {
      while (at < data.size()) {
        const Record r = readRecord(b, at, data.size(), "record in the chunk", true);
        if (r.op == kOpMessage) {
          referenced_.emplace(fixedField<std::uint32_t>(r.header, "conn", at, "message record"),
                              c.at);
          fixedField<std::uint64_t>(r.header, "time", at, "message record");
        } else if (r.op == kOpConnection) {
          connection(r, b);
        } else {
          throw Bad(at, "a " + opName(r.op) + " inside a chunk");
        }
        c.records[static_cast<std::uint32_t>(at)] = r.op;
        at = r.next();
      }
    } catch (const Bad& e) {
      throw Bad(c.at, "chunk: byte " + std::to_string(e.offset) + " of its data: " + e.what());
    }
  }

  void connection(const Record& r, Bytes& b) {
    const char* w = "connection record";
    fixedField<std::uint32_t>(r.header, "conn", r.at, w);
    stringField(r.header, "topic", r.at, w);
    // The data is the connection header (type, md5sum, message_definition, ...), header format.
    const std::vector<std::uint8_t> d = readData(b, r);
    parseFields(d.data(), d.size(), r.data_at, "connection header");
  }

  // An index record's fields and entries (12 bytes each: sec, nsec, offset in the chunk), their
  // times valid.
  struct IndexEntries {
    std::uint32_t conn = 0, count = 0;
    std::vector<std::uint8_t> data;
  };
  IndexEntries indexEntries(const Record& r) {
    const char* w = "index record";
    const std::uint32_t ver = fixedField<std::uint32_t>(r.header, "ver", r.at, w);
    IndexEntries e;
    e.conn = fixedField<std::uint32_t>(r.header, "conn", r.at, w);
    e.count = fixedField<std::uint32_t>(r.header, "count", r.at, w);
    if (ver != 1) throw Bad(r.at, "index record version " + std::to_string(ver) + " (1 is read)");
    if (static_cast<std::uint64_t>(e.count) * 12 != r.data_len)
      throw Bad(r.at, "index record of " + std::to_string(e.count) + " entries holds " +
                          std::to_string(r.data_len) + " bytes");
    e.data = readData(file_, r);
    for (std::uint32_t i = 0; i < e.count; ++i) {
      // librosbag logs and drops an entry whose time is not in [0 s 1 ns, the largest time].
      const std::uint32_t sec = u32At(e.data.data() + 12 * i);
      const std::uint32_t nsec = u32At(e.data.data() + 12 * i + 4);
      if ((sec == 0 && nsec == 0) || nsec >= 1000000000U)
        throw Bad(r.data_at + 12 * i, "index entry " + std::to_string(i) +
                                          " has an invalid time (" + std::to_string(sec) + " s " +
                                          std::to_string(nsec) + " ns)");
    }
    return e;
  }

  void index(const Record& r) {
    if (!have_chunk_) throw Bad(r.at, "an index record before any chunk");
    if (index_pos_ != 0 && r.at >= index_pos_)
      throw Bad(r.at, "an index record after the index position");
    const IndexEntries e = indexEntries(r);
    referenced_.emplace(e.conn, r.at);
    const std::vector<std::uint8_t>& d = e.data;
    for (std::uint32_t i = 0; i < e.count; ++i) {
      const std::uint32_t offset = u32At(d.data() + 12 * i + 8);
      // librosbag reads the record at `offset`, skipping connection records, and expects a
      // message record there.
      const auto& records = chunk_.records;
      auto it = records.find(offset);
      while (it != records.end() && it->second == kOpConnection) ++it;
      if (records.count(offset) == 0 || it == records.end())
        throw Bad(r.data_at + 12 * i, "index entry " + std::to_string(i) + " points at byte " +
                                          std::to_string(offset) +
                                          " of its chunk, which is not a message record");
    }
    ++index_records_[chunk_.at];
  }

  void chunkInfo(const Record& r) {
    const char* w = "chunk info record";
    const std::uint32_t ver = fixedField<std::uint32_t>(r.header, "ver", r.at, w);
    if (ver != 1) throw Bad(r.at, "chunk info version " + std::to_string(ver) + " (1 is read)");
    const std::uint64_t pos = fixedField<std::uint64_t>(r.header, "chunk_pos", r.at, w);
    fixedField<std::uint64_t>(r.header, "start_time", r.at, w);
    fixedField<std::uint64_t>(r.header, "end_time", r.at, w);
    const std::uint32_t count = fixedField<std::uint32_t>(r.header, "count", r.at, w);
    if (static_cast<std::uint64_t>(count) * 8 != r.data_len)
      throw Bad(r.at, "chunk info of " + std::to_string(count) + " connections holds " +
                          std::to_string(r.data_len) + " bytes");
    const std::vector<std::uint8_t> d = readData(file_, r);
    std::set<std::uint32_t> conns;
    for (std::uint32_t i = 0; i < count; ++i) conns.insert(u32At(d.data() + 8 * i));
    infos_.push_back({r.at, pos, conns.size()});
  }

  void finish(const std::vector<std::pair<std::uint64_t, std::uint8_t>>& top) {
    // A bag librosbag closed without a message: no connection, no chunk, its (empty) index at
    // the end of the file. Valid; the reader says it holds no messages.
    if (conn_count_ == 0 && chunk_count_ == 0 && index_pos_ == file_.size()) {
      for (const auto& [at, op] : top)
        if (op != kOpFileHeader)
          throw Bad(at, "a " + opName(op) + " in a bag whose file header announces no record");
      return;
    }
    // librosbag reads conn_count connection records from index_pos, then chunk_count chunk infos.
    auto it =
        std::find_if(top.begin(), top.end(), [&](const auto& t) { return t.first == index_pos_; });
    if (it == top.end())
      throw Bad(index_pos_, "the file header's index position is not the start of a record");
    std::set<std::uint32_t> index_conns;
    for (std::uint64_t k = 0; k < std::uint64_t{conn_count_} + chunk_count_; ++k, ++it) {
      const std::uint8_t want = k < conn_count_ ? kOpConnection : kOpChunkInfo;
      if (it == top.end())
        throw Bad(index_pos_, "the file header announces " + std::to_string(conn_count_) +
                                  " connection and " + std::to_string(chunk_count_) +
                                  " chunk info records at the index position; the file ends "
                                  "before them");
      if (it->second != want)
        throw Bad(it->first, "a " + opName(it->second) + " where the index has a " + opName(want));
    }
    // Every connection an index or message record names must be one librosbag read there.
    {
      std::uint64_t at = index_pos_;
      for (std::uint32_t k = 0; k < conn_count_; ++k) {
        const Record r = readRecord(file_, at, file_.size(), "connection record");
        index_conns.insert(fixedField<std::uint32_t>(r.header, "conn", at, "connection record"));
        at = r.next();
      }
    }
    for (const auto& [conn, at] : referenced_)
      if (index_conns.count(conn) == 0)
        throw Bad(at, "connection " + std::to_string(conn) +
                          " is used but not among the index's connection records");
    for (const auto& info : infos_) {
      const auto c = index_records_.find(info.chunk_pos);
      if (c == index_records_.end())
        throw Bad(info.at, "chunk info points at byte " + std::to_string(info.chunk_pos) +
                               ", which is not a chunk record");
      if (c->second < info.connections)
        throw Bad(info.at, "chunk info lists " + std::to_string(info.connections) +
                               " connections, but " + std::to_string(c->second) +
                               " index records follow its chunk");
    }
  }

  struct Info {
    std::uint64_t at, chunk_pos;
    std::size_t connections;
  };

  Bytes& file_;
  BagGuardLimits limits_;
  std::uint64_t index_pos_ = 0;
  std::uint32_t conn_count_ = 0, chunk_count_ = 0;
  Chunk chunk_;  // the last chunk
  bool have_chunk_ = false;
  std::map<std::uint64_t, std::size_t> index_records_;  // chunk offset -> index records after it
  std::map<std::uint32_t, std::uint64_t> referenced_;   // connection -> first record using it
  std::vector<Info> infos_;
};

// Serialized ROS messages: little-endian fixed-size fields, strings and vectors as a u32 count
// followed by their elements.
class MessageWalker {
 public:
  MessageWalker(const std::uint8_t* d, std::size_t n, const char* type)
      : d_(d), n_(n), type_(type) {}
  void skip(std::size_t bytes, const char* field) {
    if (bytes > n_ - pos_)
      throw std::runtime_error(std::string("serialized ") + type_ + ": " + field + " needs " +
                               std::to_string(bytes) + " bytes, " + std::to_string(n_ - pos_) +
                               " are left");
    pos_ += bytes;
  }
  std::uint32_t u32(const char* field) {
    skip(4, field);
    return u32At(d_ + pos_ - 4);
  }
  // A count of elements of at least `min_bytes` each.
  std::uint32_t count(const char* field, std::size_t min_bytes) {
    const std::uint32_t c = u32(field);
    if (static_cast<std::uint64_t>(c) * min_bytes > n_ - pos_)
      throw std::runtime_error(std::string("serialized ") + type_ + ": " + field + " declares " +
                               std::to_string(c) + " element(s), the " + std::to_string(n_ - pos_) +
                               " bytes left hold at most " +
                               std::to_string((n_ - pos_) / min_bytes));
    return c;
  }
  void string(const char* field) { skip(count(field, 1), field); }
  void header() {
    skip(12, "header seq and stamp");
    string("header frame_id");
  }
  std::size_t end(bool exact) {
    if (exact && pos_ != n_)
      throw std::runtime_error(std::string("serialized ") + type_ + ": " +
                               std::to_string(n_ - pos_) + " byte(s) after the message's end");
    return pos_;
  }

 private:
  const std::uint8_t* d_;
  std::size_t n_, pos_ = 0;
  const char* type_;
};

}  // namespace

void checkBagFile(const std::string& path, const BagGuardLimits& limits) {
  std::unique_ptr<FileBytes> file;
  try {
    file = std::make_unique<FileBytes>(path);
  } catch (const std::exception&) {
    throw BagError(path + ": cannot open as a ROS1 bag: cannot read the file");
  }
  try {
    Checker(*file, limits).run();
  } catch (const Bad& e) {
    throw BagError(path + ": byte " + std::to_string(e.offset) + ": " + e.what() +
                   " (corrupt bag)");
  } catch (const std::exception& e) {
    throw BagError(path + ": cannot be checked as a ROS1 bag: " + e.what());
  }
}

struct CheckedBag::Impl {
  Impl(const std::string& path, const BagGuardLimits& limits) : file(path), checker(file, limits) {}
  FileBytes file;
  Checker checker;
};

CheckedBag::CheckedBag(const std::string& path, const BagGuardLimits& limits) : path_(path) {
  try {
    impl_ = std::make_unique<Impl>(path, limits);
  } catch (const std::exception&) {
    throw BagError(path + ": cannot open as a ROS1 bag: cannot read the file");
  }
  try {
    impl_->checker.readIndex(index_);
  } catch (const Bad& e) {
    throw BagError(path + ": byte " + std::to_string(e.offset) + ": " + e.what() +
                   " (corrupt bag)");
  } catch (const std::exception& e) {
    throw BagError(path + ": cannot be checked as a ROS1 bag: " + e.what());
  }
  checked_.assign(index_.chunks.size(), false);
}

CheckedBag::~CheckedBag() = default;

void CheckedBag::checkChunk(std::size_t k) {
  if (checked_.at(k)) return;
  const BagIndex::Chunk& c = index_.chunks[k];
  try {
    impl_->checker.checkChunk(c.pos, c.index_records, index_.topics);
  } catch (const Bad& e) {
    throw BagError(path_ + ": byte " + std::to_string(e.offset) + ": " + e.what() +
                   " (corrupt bag)");
  } catch (const std::exception& e) {
    throw BagError(path_ + ": chunk at byte " + std::to_string(c.pos) + ": " + e.what());
  }
  checked_[k] = true;
  ++checked_count_;
}

std::uint64_t CheckedBag::bytesRead() const { return impl_->file.bytesRead(); }

std::size_t checkSerialized(RosMessage type, const std::uint8_t* data, std::size_t n, bool exact) {
  switch (type) {
    case RosMessage::kHeader: {
      MessageWalker w(data, n, "std_msgs/Header");
      w.header();
      return w.end(exact);
    }
    case RosMessage::kImu: {
      MessageWalker w(data, n, "sensor_msgs/Imu");
      w.header();
      // orientation (4), its covariance (9), angular velocity (3) and its covariance (9), linear
      // acceleration (3) and its covariance (9), all float64.
      w.skip(37 * 8, "orientation, angular velocity, linear acceleration and covariances");
      return w.end(exact);
    }
    case RosMessage::kPointCloud2: {
      MessageWalker w(data, n, "sensor_msgs/PointCloud2");
      w.header();
      w.skip(8, "height and width");
      // A PointField is at least a (possibly empty) name's length, offset, datatype and count.
      const std::uint32_t fields = w.count("fields", 4 + 4 + 1 + 4);
      for (std::uint32_t i = 0; i < fields; ++i) {
        w.string("field name");
        w.skip(9, "field offset, datatype and count");
      }
      w.skip(9, "is_bigendian, point_step and row_step");
      w.string("data");
      w.skip(1, "is_dense");
      return w.end(exact);
    }
  }
  return 0;
}

}  // namespace freeinit::ros1
