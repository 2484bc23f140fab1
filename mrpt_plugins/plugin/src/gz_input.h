// The byte stream under the rawlog reader: a gzip (or plain) file read forward in large chunks,
// with the position in the decompressed stream, an exact end of data (a member cut short is
// "truncated", not a clean end) and access points for random access (zlib's deflate blocks can be
// resumed from a bit position with the 32 KiB of output before it as the dictionary). Private
// to the reader (rawlog_reader.cpp).
#pragma once

#include <freeinit/mrpt_plugins/rawlog_index.h>
#include <mrpt/io/CStream.h>
#include <zlib.h>

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace freeinit::mrpt_plugins::detail {

class GzInput : public mrpt::io::CStream {
 public:
  static constexpr std::size_t kWindow = 32768;  ///< deflate's dictionary size

  GzInput() = default;
  ~GzInput() override;
  GzInput(const GzInput&) = delete;
  GzInput& operator=(const GzInput&) = delete;

  /// Opens `path`; gzip when it starts with the gzip magic, plain otherwise. Throws
  /// std::runtime_error with the system's reason.
  void open(const std::string& path);
  bool gzip() const { return gzip_; }
  std::uint64_t fileBytes() const { return file_bytes_; }

  /// Access points are appended to `sink` (when not null) every `spacing` decompressed bytes
  /// past its last one, at deflate block boundaries.
  void recordAccessPoints(std::vector<AccessPoint>* sink, std::uint64_t spacing) {
    sink_ = sink;
    spacing_ = spacing;
  }

  /// Continues decompressing at `p` (gzip: the point's input position and dictionary; plain: a
  /// file offset in p.out).
  void resume(const AccessPoint& p);
  /// Back to the start of the file.
  void rewind();
  /// Reads and drops `n` bytes; false if the data end first.
  bool discard(std::uint64_t n);

  /// No byte left (decompresses ahead if needed to know).
  bool atEnd();
  /// At the end: the file ended inside a gzip member (a truncated file).
  bool truncated() const { return truncated_; }
  /// At the end: what was wrong with the compressed data ("" if nothing).
  const std::string& error() const { return error_; }
  /// At the end: error() is a failed check of a member's trailer (its CRC-32 or length): a
  /// byte is wrong somewhere in the data decompressed before it.
  bool integrityFailed() const { return integrity_failed_; }
  /// [bytes] of the file consumed so far (progress).
  std::uint64_t compressedPosition() const;
  /// [bytes] at least as much as the decompressed data left: what is buffered, and what the rest
  /// of the file can inflate to (deflate's largest ratio is 1032:1).
  std::uint64_t remainingBound() const;

  // mrpt::io::CStream: read-only, forward-only.
  std::size_t Read(void* buffer, std::size_t count) override;
  std::size_t Write(const void* buffer, std::size_t count) override;
  std::uint64_t Seek(std::int64_t offset, CStream::TSeekOrigin origin) override;
  std::uint64_t getTotalBytesCount() const override { return file_bytes_; }
  /// [bytes] position of the next byte in the decompressed stream.
  std::uint64_t getPosition() const override { return out_total_ - (out_end_ - out_begin_); }

 private:
  bool fill();  // decompresses (or reads) more into out_; false at the end or on an error
  bool readInput();
  void resetZ(int window_bits);
  void maybeAddPoint();

  std::string path_;
  std::FILE* file_ = nullptr;
  bool gzip_ = false;
  std::uint64_t file_bytes_ = 0;
  std::uint64_t file_pos_ = 0;  ///< bytes read from the file into in_
  z_stream z_{};
  bool z_init_ = false;
  bool raw_ = false;          ///< resumed inside a member: raw deflate, the trailer is skipped
  bool member_done_ = false;  ///< a member ended: a next one may follow
  bool eof_ = false;
  bool truncated_ = false;
  std::string error_;
  bool integrity_failed_ = false;
  std::vector<unsigned char> in_, out_;
  std::size_t out_begin_ = 0, out_end_ = 0;  ///< unread bytes are out_[out_begin_, out_end_)
  std::uint64_t out_total_ = 0;              ///< decompressed bytes produced up to out_end_
  std::vector<AccessPoint>* sink_ = nullptr;
  std::uint64_t spacing_ = 0;
};

}  // namespace freeinit::mrpt_plugins::detail
