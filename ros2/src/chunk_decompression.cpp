#include "chunk_decompression.h"

#include <lz4frame.h>
#include <zstd.h>

#include <algorithm>
#include <memory>
#include <stdexcept>

namespace freeinit::ros2 {
namespace {

// The output buffer: starts small, doubles when the decoder fills it, up to the declared size
// plus one byte (so that a chunk expanding beyond its declared size is seen, not cut).
class GrowingOutput {
 public:
  GrowingOutput(std::vector<std::uint8_t>& out, std::uint64_t declared, std::size_t in_bytes)
      : out_(out), limit_(declared + 1) {
    out_.resize(static_cast<std::size_t>(std::min<std::uint64_t>(
        limit_, std::max<std::uint64_t>(4 * std::uint64_t{in_bytes}, 1 << 16))));
  }
  /// Makes room after `used` bytes; false when the limit is reached.
  bool grow(std::size_t used) {
    if (used < out_.size()) return true;
    if (out_.size() >= limit_) return false;
    out_.resize(
        static_cast<std::size_t>(std::min<std::uint64_t>(limit_, 2 * std::uint64_t{out_.size()})));
    return true;
  }
  std::uint8_t* at(std::size_t used) { return out_.data() + used; }
  std::size_t room(std::size_t used) const { return out_.size() - used; }
  /// Checks the final size against the declared one and trims the buffer to it.
  void finish(std::size_t used, const char* codec) {
    if (used != limit_ - 1)
      throw std::runtime_error(
          std::string(codec) + " data decompresses to " +
          (used >= limit_ ? "more than " + std::to_string(limit_ - 1) : std::to_string(used)) +
          " bytes, the chunk declares " + std::to_string(limit_ - 1));
    out_.resize(used);
  }

 private:
  std::vector<std::uint8_t>& out_;
  std::uint64_t limit_;
};

void zstdDecompress(const std::uint8_t* in, std::size_t n, std::uint64_t size,
                    std::vector<std::uint8_t>& out) {
  std::unique_ptr<ZSTD_DCtx, decltype(&ZSTD_freeDCtx)> ctx(ZSTD_createDCtx(), ZSTD_freeDCtx);
  if (!ctx) throw std::bad_alloc();
  GrowingOutput buffer(out, size, n);
  ZSTD_inBuffer input{in, n, 0};
  std::size_t used = 0;
  std::size_t pending = 1;  // the decoder's hint: 0 once a frame is complete and flushed
  while (input.pos < input.size || pending != 0) {
    if (!buffer.grow(used)) break;
    ZSTD_outBuffer output{buffer.at(used), buffer.room(used), 0};
    const std::size_t before = input.pos;
    pending = ZSTD_decompressStream(ctx.get(), &output, &input);
    if (ZSTD_isError(pending))
      throw std::runtime_error(std::string("zstd: ") + ZSTD_getErrorName(pending));
    used += output.pos;
    if (output.pos == 0 && input.pos == before)  // no progress: the input ends inside a frame
      throw std::runtime_error("zstd data ends inside a frame");
  }
  buffer.finish(used, "zstd");
}

void lz4Decompress(const std::uint8_t* in, std::size_t n, std::uint64_t size,
                   std::vector<std::uint8_t>& out) {
  LZ4F_dctx* raw = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&raw, LZ4F_VERSION))) throw std::bad_alloc();
  std::unique_ptr<LZ4F_dctx, decltype(&LZ4F_freeDecompressionContext)> ctx(
      raw, LZ4F_freeDecompressionContext);
  GrowingOutput buffer(out, size, n);
  std::size_t consumed = 0, used = 0;
  std::size_t pending = 1;  // 0 once a frame is complete
  while (consumed < n || pending != 0) {
    if (!buffer.grow(used)) break;
    std::size_t out_size = buffer.room(used);
    std::size_t in_size = n - consumed;
    pending =
        LZ4F_decompress(ctx.get(), buffer.at(used), &out_size, in + consumed, &in_size, nullptr);
    if (LZ4F_isError(pending))
      throw std::runtime_error(std::string("lz4: ") + LZ4F_getErrorName(pending));
    consumed += in_size;
    used += out_size;
    if (out_size == 0 && in_size == 0)  // no progress: the input ends inside a frame
      throw std::runtime_error("lz4 data ends inside a frame");
  }
  buffer.finish(used, "lz4");
}

}  // namespace

bool isSupportedCompression(const std::string& c) { return c.empty() || c == "zstd" || c == "lz4"; }

void decompressChunk(const std::string& compression, const std::uint8_t* in, std::size_t n,
                     std::uint64_t size, std::vector<std::uint8_t>& out) {
  if (compression.empty()) {
    if (n != size)
      throw std::runtime_error("an uncompressed chunk of " + std::to_string(n) +
                               " bytes declares " + std::to_string(size));
    out.assign(in, in + n);
  } else if (compression == "zstd") {
    zstdDecompress(in, n, size, out);
  } else {
    lz4Decompress(in, n, size, out);
  }
}

}  // namespace freeinit::ros2
