#include "gz_input.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace freeinit::mrpt_plugins::detail {
namespace {
constexpr std::size_t kInChunk = 1 << 20;
constexpr std::size_t kOutChunk = 1 << 20;
constexpr int kGzipBits = 15 + 16;  // zlib: gzip wrapper only
constexpr int kRawBits = -15;       // zlib: raw deflate
}  // namespace

GzInput::~GzInput() {
  if (z_init_) inflateEnd(&z_);
  if (file_ != nullptr) std::fclose(file_);
}

void GzInput::open(const std::string& path) {
  path_ = path;
  file_ = std::fopen(path.c_str(), "rb");
  if (file_ == nullptr) throw std::runtime_error(std::strerror(errno));
  if (std::fseek(file_, 0, SEEK_END) != 0) throw std::runtime_error(std::strerror(errno));
  const long size = std::ftell(file_);
  if (size < 0) throw std::runtime_error(std::strerror(errno));
  file_bytes_ = static_cast<std::uint64_t>(size);
  unsigned char magic[2] = {0, 0};
  std::rewind(file_);
  gzip_ = std::fread(magic, 1, 2, file_) == 2 && magic[0] == 0x1f && magic[1] == 0x8b;
  in_.resize(kInChunk);
  out_.resize(kWindow + kOutChunk);
  rewind();
}

void GzInput::resetZ(int window_bits) {
  if (!z_init_) {
    z_ = z_stream{};
    if (inflateInit2(&z_, window_bits) != Z_OK) throw std::runtime_error("zlib: inflateInit2");
    z_init_ = true;
  } else if (inflateReset2(&z_, window_bits) != Z_OK) {
    throw std::runtime_error("zlib: inflateReset2");
  }
  z_.next_in = in_.data();
  z_.avail_in = 0;
}

void GzInput::rewind() {
  if (std::fseek(file_, 0, SEEK_SET) != 0) throw std::runtime_error(std::strerror(errno));
  file_pos_ = 0;
  out_begin_ = out_end_ = 0;
  out_total_ = 0;
  eof_ = truncated_ = member_done_ = raw_ = false;
  error_.clear();
  if (gzip_) resetZ(kGzipBits);
}

void GzInput::resume(const AccessPoint& p) {
  eof_ = truncated_ = member_done_ = false;
  error_.clear();
  out_begin_ = out_end_ = 0;
  if (!gzip_) {
    if (std::fseek(file_, static_cast<long>(p.out), SEEK_SET) != 0)
      throw std::runtime_error(std::strerror(errno));
    file_pos_ = out_total_ = p.out;
    return;
  }
  const std::uint64_t at = p.in - (p.bits != 0 ? 1 : 0);
  if (std::fseek(file_, static_cast<long>(at), SEEK_SET) != 0)
    throw std::runtime_error(std::strerror(errno));
  file_pos_ = at;
  resetZ(kRawBits);
  raw_ = true;
  if (p.bits != 0) {
    const int c = std::fgetc(file_);
    if (c == EOF) throw std::runtime_error("the file is shorter than its index says");
    ++file_pos_;
    inflatePrime(&z_, p.bits, c >> (8 - p.bits));
  }
  if (!p.window.empty())
    inflateSetDictionary(&z_, p.window.data(), static_cast<uInt>(p.window.size()));
  std::copy(p.window.begin(), p.window.end(), out_.begin());
  out_begin_ = out_end_ = p.window.size();
  out_total_ = p.out;
}

bool GzInput::readInput() {
  const std::size_t n = std::fread(in_.data(), 1, in_.size(), file_);
  if (n == 0) {
    if (std::ferror(file_)) error_ = std::string("read error: ") + std::strerror(errno);
    return false;
  }
  file_pos_ += n;
  z_.next_in = in_.data();
  z_.avail_in = static_cast<uInt>(n);
  return true;
}

std::uint64_t GzInput::compressedPosition() const {
  return gzip_ ? file_pos_ - z_.avail_in : getPosition();
}

std::uint64_t GzInput::remainingBound() const {
  const std::uint64_t buffered = out_end_ - out_begin_;
  const std::uint64_t unread = file_bytes_ > file_pos_ ? file_bytes_ - file_pos_ : 0;
  if (!gzip_) return buffered + unread;
  return buffered + 1032 * (unread + z_.avail_in);
}

void GzInput::maybeAddPoint() {
  // Between two deflate blocks (bit 128), not inside the last one (bit 64).
  if (sink_ == nullptr || (z_.data_type & 128) == 0 || (z_.data_type & 64) != 0) return;
  const auto written = static_cast<std::size_t>(z_.next_out - out_.data());
  const std::uint64_t out = out_total_ + (written - out_end_);
  if (out == 0) return;
  if (out < (sink_->empty() ? spacing_ : sink_->back().out + spacing_)) return;
  AccessPoint p;
  p.in = file_pos_ - z_.avail_in;
  p.bits = z_.data_type & 7;
  p.out = out;
  const std::size_t n = std::min<std::size_t>(kWindow, written);
  p.window.assign(out_.begin() + static_cast<std::ptrdiff_t>(written - n),
                  out_.begin() + static_cast<std::ptrdiff_t>(written));
  sink_->push_back(std::move(p));
}

bool GzInput::fill() {
  if (eof_) return false;
  // Keep the last 32 KiB of output before the new data: the dictionary of an access point.
  const std::size_t keep = std::min(kWindow, out_end_);
  std::memmove(out_.data(), out_.data() + (out_end_ - keep), keep);
  out_begin_ = out_end_ = keep;
  if (!gzip_) {
    const std::size_t n = std::fread(out_.data() + keep, 1, out_.size() - keep, file_);
    if (n == 0) {
      if (std::ferror(file_)) error_ = std::string("read error: ") + std::strerror(errno);
      eof_ = true;
      return false;
    }
    file_pos_ += n;
    out_end_ += n;
    out_total_ += n;
    return true;
  }
  z_.next_out = out_.data() + out_end_;
  z_.avail_out = static_cast<uInt>(out_.size() - out_end_);
  while (z_.avail_out > 0) {
    if (z_.avail_in == 0 && !readInput()) {
      // The file ends: cleanly after a whole member, else inside one.
      if (!member_done_ && error_.empty()) truncated_ = true;
      eof_ = true;
      break;
    }
    if (member_done_) {  // bytes after a member: the next member's header
      Bytef* const next = z_.next_in;
      const uInt avail = z_.avail_in;
      resetZ(kGzipBits);
      z_.next_in = next;
      z_.avail_in = avail;
      member_done_ = raw_ = false;
      continue;
    }
    const int rc = inflate(&z_, Z_BLOCK);
    if (rc == Z_STREAM_END) {
      if (raw_) {
        // Resumed inside the member: its 8-byte trailer (CRC-32, size) was not parsed by zlib.
        for (int skip = 8; skip > 0;) {
          if (z_.avail_in == 0 && !readInput()) break;
          const uInt n = std::min<uInt>(z_.avail_in, static_cast<uInt>(skip));
          z_.next_in += n;
          z_.avail_in -= n;
          skip -= static_cast<int>(n);
        }
      }
      member_done_ = true;
      continue;
    }
    if (rc == Z_OK || rc == Z_BUF_ERROR) {
      maybeAddPoint();
      continue;
    }
    const std::string zmsg = z_.msg != nullptr ? z_.msg : "";
    integrity_failed_ = zmsg == "incorrect data check" || zmsg == "incorrect length check";
    if (integrity_failed_)
      // The member's trailer is read after its last byte: the damage is anywhere before it.
      error_ = std::string("the gzip stream's ") +
               (zmsg == "incorrect data check" ? "CRC-32" : "length") +
               " does not match its data (checked at byte " +
               std::to_string(file_pos_ - z_.avail_in) +
               " of the file, its end): a byte is wrong somewhere in the stream, not "
               "necessarily here, so every record read from it is suspect";
    else
      error_ = std::string("corrupt gzip data near byte ") +
               std::to_string(file_pos_ - z_.avail_in) + " of the file" +
               (zmsg.empty() ? std::string() : " (zlib: " + zmsg + ")");
    eof_ = true;
    break;
  }
  const std::size_t produced = static_cast<std::size_t>(z_.next_out - out_.data()) - out_end_;
  out_end_ += produced;
  out_total_ += produced;
  return produced > 0;
}

bool GzInput::atEnd() { return out_begin_ == out_end_ && !fill(); }

std::size_t GzInput::Read(void* buffer, std::size_t count) {
  auto* dst = static_cast<unsigned char*>(buffer);
  std::size_t done = 0;
  while (done < count) {
    if (out_begin_ == out_end_ && !fill()) break;
    const std::size_t n = std::min(count - done, out_end_ - out_begin_);
    std::memcpy(dst + done, out_.data() + out_begin_, n);
    out_begin_ += n;
    done += n;
  }
  return done;
}

bool GzInput::discard(std::uint64_t n) {
  while (n > 0) {
    if (out_begin_ == out_end_ && !fill()) return false;
    const auto take = static_cast<std::size_t>(std::min<std::uint64_t>(n, out_end_ - out_begin_));
    out_begin_ += take;
    n -= take;
  }
  return true;
}

std::size_t GzInput::Write(const void*, std::size_t) {
  throw std::logic_error("GzInput is read-only");
}

std::uint64_t GzInput::Seek(std::int64_t, CStream::TSeekOrigin) {
  throw std::logic_error("GzInput cannot seek (use resume)");
}

}  // namespace freeinit::mrpt_plugins::detail
