// The Free-Init live stream wire format (docs/wire_format.md): Doppler LiDAR frames and IMU samples
// in UDP datagrams, each with magic, version, sender session id, per-datagram sequence number and
// a CRC32. Frames larger than one datagram are split into chunks. Little-endian throughout.
//
// This file only encodes and decodes single datagrams; ordering, duplicates, losses and frame
// reassembly are StreamReceiver's job. No MRPT here, so it is unit-testable in milliseconds.
#pragma once

#include <freeinit/types.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace freeinit::net {

inline constexpr std::uint32_t kMagic = 0x4C444946;  ///< bytes "FIDL"
inline constexpr std::uint8_t kVersion = 1;
inline constexpr std::size_t kHeaderBytes = 32;
inline constexpr std::size_t kCrcBytes = 4;
inline constexpr std::size_t kImuSampleBytes = 56;     ///< i64 stamp + 6 f64
inline constexpr std::size_t kChunkHeaderBytes = 128;  ///< frame chunk header in the payload
inline constexpr std::size_t kPointBytes = 26;         ///< 6 f32 + u16
inline constexpr std::size_t kMaxDatagram = 65507;     ///< largest UDP/IPv4 payload
inline constexpr std::size_t kMinDatagram =
    kHeaderBytes + kChunkHeaderBytes + kPointBytes + kCrcBytes;  ///< room for one point per chunk
inline constexpr std::uint32_t kMaxFramePoints = 4'000'000;
/// Stamps [ns] outside [0, kMaxStampNs) are rejected (year 1970 .. ~2116): every accepted stamp
/// converts to MRPT's clock and back, and +/- a few seconds of arithmetic on it cannot overflow.
inline constexpr std::int64_t kMaxStampNs = std::int64_t{1} << 62;
inline bool validStamp(std::int64_t ns) { return ns >= 0 && ns < kMaxStampNs; }

enum class PacketType : std::uint8_t { Imu = 1, FrameChunk = 2, EndOfStream = 3 };

/// One IMU sample; the stamp is integer nanoseconds since the UNIX epoch so that it crosses the
/// wire exactly (MRPT's 100 ns clock ticks convert without rounding).
struct ImuMessage {
  std::int64_t stamp_ns = 0;
  Vec3 gyro = Vec3::Zero();   ///< [rad/s] body frame
  Vec3 accel = Vec3::Zero();  ///< [m/s^2] specific force, body frame
};

/// One LiDAR frame: points in the LiDAR frame, point time = stamp + time_offset.
struct FrameMessage {
  std::uint32_t frame_id = 0;  ///< set by the sender, increments per frame within a session
  std::int64_t stamp_ns = 0;
  Extrinsics extrinsics;  ///< LiDAR pose in the body (IMU) frame
  std::vector<DopplerPoint> points;
};

/// The fixed datagram header.
struct PacketHeader {
  PacketType type = PacketType::Imu;
  std::uint64_t session = 0;   ///< random per sender start: a new value means the sender restarted
  std::uint64_t sequence = 0;  ///< per datagram, from 0 at the session start, +1 per datagram
};

/// One frame chunk as decoded (its points are a slice of the frame).
struct FrameChunk {
  std::uint32_t frame_id = 0;
  std::uint16_t chunk_index = 0, chunk_count = 0;
  std::uint32_t total_points = 0, first_point = 0;
  std::int64_t stamp_ns = 0;
  Extrinsics extrinsics;
  std::vector<DopplerPoint> points;
};

/// A decoded, checked datagram.
struct Packet {
  PacketHeader header;
  std::vector<ImuMessage> imu;       ///< type Imu
  FrameChunk chunk;                  ///< type FrameChunk
  std::uint64_t datagrams_sent = 0;  ///< type EndOfStream: datagrams the session sent before it
};

/// Why a datagram was rejected.
enum class DecodeError { None, TooShort, BadMagic, BadVersion, BadLength, BadCrc, BadContent };
const char* toString(DecodeError e);

/// IEEE 802.3 CRC32 (the zlib/PNG one).
std::uint32_t crc32(const std::uint8_t* data, std::size_t n);

/// Points per chunk for a datagram size limit (bytes, kMinDatagram..kMaxDatagram).
std::size_t pointsPerChunk(std::size_t max_datagram);

/// Encoders: each returns whole datagrams, the sequence numbers taken from `next_sequence`, which
/// is advanced. Throws std::invalid_argument on a message the format cannot carry.
std::vector<std::uint8_t> encodeImu(const std::vector<ImuMessage>& samples, std::uint64_t session,
                                    std::uint64_t& next_sequence);
/// Chunks a frame of `points` needs. Throws std::invalid_argument if it cannot be carried.
std::size_t chunkCount(std::size_t points, std::size_t max_datagram);
/// One chunk (points [chunk * pointsPerChunk, ...)), so that a sender can stream a frame as its
/// points are measured.
std::vector<std::uint8_t> encodeFrameChunk(const FrameMessage& frame, std::size_t chunk,
                                           std::uint64_t session, std::uint64_t& next_sequence,
                                           std::size_t max_datagram);
std::vector<std::vector<std::uint8_t>> encodeFrame(const FrameMessage& frame, std::uint64_t session,
                                                   std::uint64_t& next_sequence,
                                                   std::size_t max_datagram);
std::vector<std::uint8_t> encodeEndOfStream(std::uint64_t session, std::uint64_t& next_sequence);

/// Decodes one datagram; on failure returns the reason and leaves `out` unspecified.
/// Never reads outside [data, data + n).
DecodeError decode(const std::uint8_t* data, std::size_t n, Packet& out);

}  // namespace freeinit::net
