// CRC-32 (IEEE 802.3, reflected polynomial 0xEDB88320): the checksum MCAP stores for chunks.
#pragma once

#include <cstddef>
#include <cstdint>

namespace freeinit::ros2 {

std::uint32_t crc32(const std::uint8_t* data, std::size_t size);

}  // namespace freeinit::ros2
