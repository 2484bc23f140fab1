// Fuzz harness: one datagram through the live wire format's decoder, twice: as it is, and with
// its length field and CRC made consistent (so that the content checks behind the CRC are reached
// by mutation too). Invariants: a decoded datagram's content is what the checks promise (counts
// within the datagram, stamps valid, chunk within its frame), and IMU and end-of-stream datagrams
// re-encode to datagrams that decode to the same content.
#include <freeinit/net/wire_format.h>

#include <cstring>
#include <vector>

#include "harness.h"
#include "wire_patch.h"

namespace freeinit::fuzz {
namespace {

std::string check(const std::uint8_t* data, std::size_t size) {
  net::Packet p;
  const net::DecodeError e = net::decode(data, size, p);
  if (e != net::DecodeError::None) return net::toString(e);
  switch (p.header.type) {
    case net::PacketType::Imu: {
      if (p.imu.empty()) broken("IMU datagram without samples");
      for (const auto& s : p.imu)
        if (!net::validStamp(s.stamp_ns) || !s.gyro.allFinite() || !s.accel.allFinite())
          broken("invalid IMU sample decoded");
      std::uint64_t seq = p.header.sequence;
      const auto again = net::encodeImu(p.imu, p.header.session, seq);
      net::Packet q;
      if (net::decode(again.data(), again.size(), q) != net::DecodeError::None ||
          q.imu.size() != p.imu.size())
        broken("IMU datagram does not round-trip");
      for (std::size_t i = 0; i < p.imu.size(); ++i)
        if (q.imu[i].stamp_ns != p.imu[i].stamp_ns || q.imu[i].gyro != p.imu[i].gyro ||
            q.imu[i].accel != p.imu[i].accel)
          broken("IMU sample does not round-trip");
      return "imu";
    }
    case net::PacketType::FrameChunk: {
      const net::FrameChunk& c = p.chunk;
      if (c.points.empty() || c.chunk_index >= c.chunk_count ||
          c.total_points > net::kMaxFramePoints ||
          std::uint64_t{c.first_point} + c.points.size() > c.total_points)
        broken("inconsistent chunk decoded");
      return "chunk";
    }
    case net::PacketType::EndOfStream: {
      std::uint64_t seq = p.header.sequence;
      const auto again = net::encodeEndOfStream(p.header.session, seq);
      net::Packet q;
      if (net::decode(again.data(), again.size(), q) != net::DecodeError::None ||
          q.header.session != p.header.session || q.header.sequence != p.header.sequence)
        broken("end of stream does not round-trip");
      return "end";
    }
  }
  broken("unknown packet type decoded");
}

}  // namespace

std::string fuzzOne(const std::uint8_t* data, std::size_t size) {
  const std::string as_is = check(data, size);
  std::vector<std::uint8_t> patched(data, data + size);
  patchLengthAndCrc(patched);
  const std::string fixed = check(patched.data(), patched.size());
  return "ok: as is " + as_is + ", with length and CRC fixed " + fixed;
}

}  // namespace freeinit::fuzz
