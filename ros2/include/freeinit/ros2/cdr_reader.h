// Reads the primitive values of one CDR-serialized ROS 2 message (OMG CDR version 1, as rmw
// implementations and rosbag2 write it):
//   - a 4-byte encapsulation header: 00 01 (CDR, little endian) or 00 00 (CDR, big endian), then
//     two option bytes (ignored);
//   - each value aligned to its size (8 for float64), counted from the end of that header;
//   - a string: uint32 length including the terminating NUL, the bytes, the NUL;
//   - a sequence: uint32 element count, then the elements.
// Every length and count is checked against the bytes left before anything is allocated, so a
// corrupt message can make a decoder allocate no more than its own size (a sequence of n elements
// is refused unless n times the smallest element fits in what is left).
#pragma once

#include <freeinit/ros2/recording_error.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace freeinit::ros2 {

/// A CDR message that cannot be decoded; the message names the field and what is wrong.
class CdrError : public RecordingError {
 public:
  using RecordingError::RecordingError;
};

class CdrReader {
 public:
  /// Reads the encapsulation header of the `size` bytes at `data` (which must outlive the reader).
  /// Throws CdrError for fewer than 4 bytes, or an encapsulation other than plain CDR (parameter
  /// lists, XCDR2), naming it.
  CdrReader(const std::uint8_t* data, std::size_t size);

  bool bigEndian() const { return big_endian_; }
  /// [bytes] not read yet.
  std::size_t remaining() const { return size_ - pos_; }

  // Each reads one aligned value; `what` names the field in error messages.
  std::uint8_t uint8(const char* what);
  bool boolean(const char* what);  ///< a byte; any value other than 0 or 1 is an error
  std::int32_t int32(const char* what);
  std::uint32_t uint32(const char* what);
  double float64(const char* what);
  std::string string(const char* what);
  /// A sequence's element count, refused unless `count * min_element_bytes` fits in what is left.
  std::uint32_t sequenceLength(std::size_t min_element_bytes, const char* what);
  /// A uint8[] sequence into `out`.
  void bytes(std::vector<std::uint8_t>& out, const char* what);

 private:
  /// Skips the padding before a value of `n` bytes and checks that it fits.
  const std::uint8_t* take(std::size_t n, const char* what);
  template <class T>
  T value(const char* what);

  const std::uint8_t* data_;  ///< after the encapsulation header
  std::size_t size_;
  std::size_t pos_ = 0;
  bool big_endian_ = false;
};

}  // namespace freeinit::ros2
