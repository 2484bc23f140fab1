// A file read at given offsets (pread), with its size known up front, so that every length a
// reader finds in it can be checked against what the file holds before anything is allocated.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace freeinit::ros2 {

class InputFile {
 public:
  /// Opens `path` for reading. Throws std::runtime_error with the system's reason.
  explicit InputFile(const std::string& path);
  ~InputFile();
  InputFile(const InputFile&) = delete;
  InputFile& operator=(const InputFile&) = delete;

  std::uint64_t size() const { return size_; }  ///< [bytes]
  /// Reads `n` bytes at `offset` into `out` (resized to n). Precondition: offset + n <= size().
  /// Throws std::runtime_error on a read error or a file that shrank.
  void read(std::uint64_t offset, std::size_t n, std::vector<std::uint8_t>& out) const;

 private:
  int fd_ = -1;
  std::uint64_t size_ = 0;
};

}  // namespace freeinit::ros2
