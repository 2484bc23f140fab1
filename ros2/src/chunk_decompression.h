// Decompression of MCAP chunks: "" (none), "zstd" (one or more zstd frames) and "lz4" (the LZ4
// frame format). The output grows with what the decoder actually produces, never beyond the size
// the chunk declares: a corrupt size field cannot make it allocate more than the data expands to.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace freeinit::ros2 {

/// True for "", "zstd" and "lz4".
bool isSupportedCompression(const std::string& compression);

/// Decompresses the `n` bytes at `in` into `out`, which must then hold exactly `size` bytes.
/// Throws std::runtime_error saying what is wrong (the decoder's error, data that ends inside a
/// frame, more or fewer bytes than declared). Precondition: isSupportedCompression(compression).
void decompressChunk(const std::string& compression, const std::uint8_t* in, std::size_t n,
                     std::uint64_t size, std::vector<std::uint8_t>& out);

}  // namespace freeinit::ros2
