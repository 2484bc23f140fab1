#include <freeinit/net/wire_format.h>

#include <array>
#include <cmath>
#include <cstring>
#include <stdexcept>

namespace freeinit::net {
namespace {

// Little-endian writer/reader over a byte buffer. Floats travel as their IEEE-754 bit patterns.
class Writer {
 public:
  explicit Writer(std::vector<std::uint8_t>& b) : b_(b) {}
  void u8(std::uint8_t v) { b_.push_back(v); }
  void u16(std::uint16_t v) { uint(v, 2); }
  void u32(std::uint32_t v) { uint(v, 4); }
  void u64(std::uint64_t v) { uint(v, 8); }
  void i64(std::int64_t v) { uint(static_cast<std::uint64_t>(v), 8); }
  void f32(float v) {
    std::uint32_t u;
    std::memcpy(&u, &v, 4);
    u32(u);
  }
  void f64(double v) {
    std::uint64_t u;
    std::memcpy(&u, &v, 8);
    u64(u);
  }

 private:
  void uint(std::uint64_t v, int bytes) {
    for (int i = 0; i < bytes; ++i) b_.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  std::vector<std::uint8_t>& b_;
};

class Reader {
 public:
  Reader(const std::uint8_t* d, std::size_t n) : d_(d), n_(n) {}
  std::size_t left() const { return n_ - pos_; }
  std::uint8_t u8() { return static_cast<std::uint8_t>(uint(1)); }
  std::uint16_t u16() { return static_cast<std::uint16_t>(uint(2)); }
  std::uint32_t u32() { return static_cast<std::uint32_t>(uint(4)); }
  std::uint64_t u64() { return uint(8); }
  std::int64_t i64() { return static_cast<std::int64_t>(uint(8)); }
  float f32() {
    const std::uint32_t u = u32();
    float v;
    std::memcpy(&v, &u, 4);
    return v;
  }
  double f64() {
    const std::uint64_t u = u64();
    double v;
    std::memcpy(&v, &u, 8);
    return v;
  }

 private:
  // Callers check left() first; reading past the end is a programming error.
  std::uint64_t uint(int bytes) {
    if (left() < static_cast<std::size_t>(bytes)) throw std::logic_error("wire reader overrun");
    std::uint64_t v = 0;
    for (int i = 0; i < bytes; ++i) v |= static_cast<std::uint64_t>(d_[pos_ + i]) << (8 * i);
    pos_ += static_cast<std::size_t>(bytes);
    return v;
  }
  const std::uint8_t* d_;
  std::size_t n_, pos_ = 0;
};

std::array<std::uint32_t, 256> makeCrcTable() {
  std::array<std::uint32_t, 256> t{};
  for (std::uint32_t i = 0; i < 256; ++i) {
    std::uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1U) ? 0xEDB88320U ^ (c >> 1) : c >> 1;
    t[i] = c;
  }
  return t;
}

// Header with a zero payload length; finish() patches the length and appends the CRC.
std::vector<std::uint8_t> begin(PacketType type, std::uint64_t session, std::uint64_t& seq) {
  std::vector<std::uint8_t> b;
  Writer w(b);
  w.u32(kMagic);
  w.u8(kVersion);
  w.u8(static_cast<std::uint8_t>(type));
  w.u16(static_cast<std::uint16_t>(kHeaderBytes));
  w.u64(session);
  w.u64(seq++);
  w.u32(0);  // payload bytes, patched by finish()
  w.u32(0);  // reserved
  return b;
}

void finish(std::vector<std::uint8_t>& b) {
  const auto payload = static_cast<std::uint32_t>(b.size() - kHeaderBytes);
  for (int i = 0; i < 4; ++i) b[24 + i] = static_cast<std::uint8_t>(payload >> (8 * i));
  const std::uint32_t c = crc32(b.data(), b.size());
  Writer(b).u32(c);
}

void writeExtrinsics(Writer& w, const Extrinsics& e) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) w.f64(e.R_bl(r, c));
  for (int i = 0; i < 3; ++i) w.f64(e.p_bl(i));
}

Extrinsics readExtrinsics(Reader& r) {
  Extrinsics e;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) e.R_bl(i, j) = r.f64();
  for (int i = 0; i < 3; ++i) e.p_bl(i) = r.f64();
  return e;
}

}  // namespace

const char* toString(DecodeError e) {
  switch (e) {
    case DecodeError::None:
      return "ok";
    case DecodeError::TooShort:
      return "shorter than a header";
    case DecodeError::BadMagic:
      return "bad magic";
    case DecodeError::BadVersion:
      return "unsupported version";
    case DecodeError::BadLength:
      return "length fields disagree with the datagram size";
    case DecodeError::BadCrc:
      return "CRC mismatch";
    case DecodeError::BadContent:
      return "inconsistent content";
  }
  return "?";
}

std::uint32_t crc32(const std::uint8_t* data, std::size_t n) {
  static const std::array<std::uint32_t, 256> table = makeCrcTable();
  std::uint32_t c = 0xFFFFFFFFU;
  for (std::size_t i = 0; i < n; ++i) c = table[(c ^ data[i]) & 0xFFU] ^ (c >> 8);
  return c ^ 0xFFFFFFFFU;
}

std::size_t pointsPerChunk(std::size_t max_datagram) {
  if (max_datagram < kMinDatagram || max_datagram > kMaxDatagram)
    throw std::invalid_argument("datagram size limit must be in [" + std::to_string(kMinDatagram) +
                                ", " + std::to_string(kMaxDatagram) + "] bytes");
  return (max_datagram - kHeaderBytes - kChunkHeaderBytes - kCrcBytes) / kPointBytes;
}

std::vector<std::uint8_t> encodeImu(const std::vector<ImuMessage>& samples, std::uint64_t session,
                                    std::uint64_t& next_sequence) {
  const std::size_t max_samples = (kMaxDatagram - kHeaderBytes - 4 - kCrcBytes) / kImuSampleBytes;
  if (samples.empty() || samples.size() > max_samples)
    throw std::invalid_argument("an IMU datagram carries 1.." + std::to_string(max_samples) +
                                " samples");
  std::vector<std::uint8_t> b = begin(PacketType::Imu, session, next_sequence);
  Writer w(b);
  w.u16(static_cast<std::uint16_t>(samples.size()));
  w.u16(0);
  for (const auto& s : samples) {
    w.i64(s.stamp_ns);
    for (int i = 0; i < 3; ++i) w.f64(s.gyro(i));
    for (int i = 0; i < 3; ++i) w.f64(s.accel(i));
  }
  finish(b);
  return b;
}

std::size_t chunkCount(std::size_t points, std::size_t max_datagram) {
  const std::size_t per_chunk = pointsPerChunk(max_datagram);
  if (points == 0 || points > kMaxFramePoints)
    throw std::invalid_argument("a frame carries 1.." + std::to_string(kMaxFramePoints) +
                                " points, not " + std::to_string(points));
  const std::size_t chunks = (points + per_chunk - 1) / per_chunk;
  if (chunks > 0xFFFF)
    throw std::invalid_argument("frame needs " + std::to_string(chunks) +
                                " chunks (at most 65535): use larger datagrams");
  return chunks;
}

std::vector<std::uint8_t> encodeFrameChunk(const FrameMessage& frame, std::size_t chunk,
                                           std::uint64_t session, std::uint64_t& next_sequence,
                                           std::size_t max_datagram) {
  const std::size_t n = frame.points.size();
  const std::size_t chunks = chunkCount(n, max_datagram);
  if (chunk >= chunks)
    throw std::invalid_argument("chunk " + std::to_string(chunk) + " of a frame of " +
                                std::to_string(chunks));
  const std::size_t per_chunk = pointsPerChunk(max_datagram);
  const std::size_t first = chunk * per_chunk;
  const std::size_t m = std::min(per_chunk, n - first);
  std::vector<std::uint8_t> b = begin(PacketType::FrameChunk, session, next_sequence);
  b.reserve(kHeaderBytes + kChunkHeaderBytes + m * kPointBytes + kCrcBytes);
  Writer w(b);
  w.u32(frame.frame_id);
  w.u16(static_cast<std::uint16_t>(chunk));
  w.u16(static_cast<std::uint16_t>(chunks));
  w.u32(static_cast<std::uint32_t>(n));
  w.u32(static_cast<std::uint32_t>(first));
  w.u32(static_cast<std::uint32_t>(m));
  w.u32(0);
  w.i64(frame.stamp_ns);
  writeExtrinsics(w, frame.extrinsics);
  for (std::size_t i = first; i < first + m; ++i) {
    const DopplerPoint& p = frame.points[i];
    w.f32(p.p_l.x());
    w.f32(p.p_l.y());
    w.f32(p.p_l.z());
    w.f32(p.doppler);
    w.f32(p.time_offset);
    w.f32(p.intensity);
    w.u16(p.line);
  }
  finish(b);
  return b;
}

std::vector<std::vector<std::uint8_t>> encodeFrame(const FrameMessage& frame, std::uint64_t session,
                                                   std::uint64_t& next_sequence,
                                                   std::size_t max_datagram) {
  const std::size_t chunks = chunkCount(frame.points.size(), max_datagram);
  std::vector<std::vector<std::uint8_t>> out;
  out.reserve(chunks);
  for (std::size_t c = 0; c < chunks; ++c)
    out.push_back(encodeFrameChunk(frame, c, session, next_sequence, max_datagram));
  return out;
}

std::vector<std::uint8_t> encodeEndOfStream(std::uint64_t session, std::uint64_t& next_sequence) {
  const std::uint64_t sent_before = next_sequence;
  std::vector<std::uint8_t> b = begin(PacketType::EndOfStream, session, next_sequence);
  Writer(b).u64(sent_before);
  finish(b);
  return b;
}

DecodeError decode(const std::uint8_t* data, std::size_t n, Packet& out) {
  if (n < kHeaderBytes + kCrcBytes) return DecodeError::TooShort;
  Reader r(data, n);
  if (r.u32() != kMagic) return DecodeError::BadMagic;
  if (r.u8() != kVersion) return DecodeError::BadVersion;
  const std::uint8_t type = r.u8();
  const std::uint16_t header_bytes = r.u16();
  out.header.session = r.u64();
  out.header.sequence = r.u64();
  const std::uint32_t payload = r.u32();
  r.u32();  // reserved
  if (header_bytes != kHeaderBytes ||
      static_cast<std::size_t>(payload) + kHeaderBytes + kCrcBytes != n)
    return DecodeError::BadLength;
  Reader crc_reader(data + n - kCrcBytes, kCrcBytes);
  if (crc_reader.u32() != crc32(data, n - kCrcBytes)) return DecodeError::BadCrc;

  Reader p(data + kHeaderBytes, payload);
  switch (type) {
    case static_cast<std::uint8_t>(PacketType::Imu): {
      out.header.type = PacketType::Imu;
      if (p.left() < 4) return DecodeError::BadLength;
      const std::uint16_t count = p.u16();
      p.u16();
      if (count == 0 || p.left() != count * kImuSampleBytes) return DecodeError::BadLength;
      out.imu.resize(count);
      for (auto& s : out.imu) {
        s.stamp_ns = p.i64();
        for (int i = 0; i < 3; ++i) s.gyro(i) = p.f64();
        for (int i = 0; i < 3; ++i) s.accel(i) = p.f64();
        if (!validStamp(s.stamp_ns) || !s.gyro.allFinite() || !s.accel.allFinite())
          return DecodeError::BadContent;
      }
      return DecodeError::None;
    }
    case static_cast<std::uint8_t>(PacketType::FrameChunk): {
      out.header.type = PacketType::FrameChunk;
      if (p.left() < kChunkHeaderBytes) return DecodeError::BadLength;
      FrameChunk& c = out.chunk;
      c.frame_id = p.u32();
      c.chunk_index = p.u16();
      c.chunk_count = p.u16();
      c.total_points = p.u32();
      c.first_point = p.u32();
      const std::uint32_t m = p.u32();
      p.u32();
      c.stamp_ns = p.i64();
      c.extrinsics = readExtrinsics(p);
      if (p.left() != static_cast<std::size_t>(m) * kPointBytes) return DecodeError::BadLength;
      if (m == 0 || c.chunk_count == 0 || c.chunk_index >= c.chunk_count ||
          c.total_points > kMaxFramePoints ||
          static_cast<std::uint64_t>(c.first_point) + m > c.total_points ||
          !validStamp(c.stamp_ns) || !c.extrinsics.R_bl.allFinite() ||
          !c.extrinsics.p_bl.allFinite())
        return DecodeError::BadContent;
      c.points.resize(m);
      for (auto& pt : c.points) {
        pt.p_l.x() = p.f32();
        pt.p_l.y() = p.f32();
        pt.p_l.z() = p.f32();
        pt.doppler = p.f32();
        pt.time_offset = p.f32();
        pt.intensity = p.f32();
        pt.line = p.u16();
      }
      return DecodeError::None;
    }
    case static_cast<std::uint8_t>(PacketType::EndOfStream): {
      out.header.type = PacketType::EndOfStream;
      if (p.left() != 8) return DecodeError::BadLength;
      out.datagrams_sent = p.u64();
      return DecodeError::None;
    }
    default:
      return DecodeError::BadContent;
  }
}

}  // namespace freeinit::net
