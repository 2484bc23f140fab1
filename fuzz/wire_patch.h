// Makes a datagram's payload length and CRC consistent with its size, so that mutated datagrams
// reach the checks behind the CRC (shared by the wire-format and stream-receiver harnesses).
#pragma once

#include <freeinit/net/wire_format.h>

#include <vector>

namespace freeinit::fuzz {

inline void patchLengthAndCrc(std::vector<std::uint8_t>& d) {
  if (d.size() < net::kHeaderBytes + net::kCrcBytes) return;
  const auto payload = static_cast<std::uint32_t>(d.size() - net::kHeaderBytes - net::kCrcBytes);
  for (int i = 0; i < 4; ++i) d[24 + i] = static_cast<std::uint8_t>(payload >> (8 * i));
  const std::uint32_t c = net::crc32(d.data(), d.size() - net::kCrcBytes);
  for (int i = 0; i < 4; ++i) d[d.size() - 4 + i] = static_cast<std::uint8_t>(c >> (8 * i));
}

}  // namespace freeinit::fuzz
