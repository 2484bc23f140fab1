#include <freeinit/ros2/cdr_reader.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <string>

namespace freeinit::ros2 {
namespace {

constexpr std::size_t kEncapsulationBytes = 4;

// The representation identifiers of the RTPS / XTypes specifications.
const char* encapsulationName(unsigned id) {
  switch (id) {
    case 0x00:
      return "CDR_BE";
    case 0x01:
      return "CDR_LE";
    case 0x02:
      return "PL_CDR_BE, a parameter list";
    case 0x03:
      return "PL_CDR_LE, a parameter list";
    case 0x06:
      return "CDR2_BE, XCDR version 2";
    case 0x07:
      return "CDR2_LE, XCDR version 2";
    case 0x08:
      return "D_CDR2_BE, XCDR version 2";
    case 0x09:
      return "D_CDR2_LE, XCDR version 2";
    case 0x0a:
      return "PL_CDR2_BE, XCDR version 2";
    case 0x0b:
      return "PL_CDR2_LE, XCDR version 2";
    default:
      return "unknown";
  }
}

std::string hex2(unsigned a, unsigned b) {
  const char* digits = "0123456789abcdef";
  return {digits[a >> 4], digits[a & 15], ' ', digits[b >> 4], digits[b & 15]};
}

}  // namespace

CdrReader::CdrReader(const std::uint8_t* data, std::size_t size) {
  if (size < kEncapsulationBytes)
    throw CdrError("a CDR message of " + std::to_string(size) +
                   " bytes, shorter than its 4-byte encapsulation header");
  const unsigned id = (unsigned{data[0]} << 8) | data[1];
  if (id != 0x00 && id != 0x01)
    throw CdrError("encapsulation " + hex2(data[0], data[1]) + " (" + encapsulationName(id) +
                   ") is not supported: only plain CDR (00 00 big endian, 00 01 little endian)");
  big_endian_ = id == 0x00;
  data_ = data + kEncapsulationBytes;
  size_ = size - kEncapsulationBytes;
}

const std::uint8_t* CdrReader::take(std::size_t n, const char* what) {
  const std::size_t padding = (n - pos_ % n) % n;
  if (padding + n > remaining())
    throw CdrError(std::string(what) + ": needs " + std::to_string(n) + " bytes at byte " +
                   std::to_string(kEncapsulationBytes + pos_ + padding) + ", the message has " +
                   std::to_string(kEncapsulationBytes + size_));
  pos_ += padding;
  const std::uint8_t* p = data_ + pos_;
  pos_ += n;
  return p;
}

template <class T>
T CdrReader::value(const char* what) {
  std::array<std::uint8_t, sizeof(T)> b;
  std::memcpy(b.data(), take(sizeof(T), what), sizeof(T));
  static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "little-endian host assumed");
  if (big_endian_) std::reverse(b.begin(), b.end());
  T v;
  std::memcpy(&v, b.data(), sizeof(T));
  return v;
}

std::uint8_t CdrReader::uint8(const char* what) { return *take(1, what); }

bool CdrReader::boolean(const char* what) {
  const std::uint8_t v = *take(1, what);
  if (v > 1) throw CdrError(std::string(what) + ": boolean of value " + std::to_string(v));
  return v == 1;
}

std::int32_t CdrReader::int32(const char* what) { return value<std::int32_t>(what); }
std::uint32_t CdrReader::uint32(const char* what) { return value<std::uint32_t>(what); }
double CdrReader::float64(const char* what) { return value<double>(what); }

std::string CdrReader::string(const char* what) {
  const std::uint32_t n = uint32(what);
  if (n == 0) return {};  // not what ROS 2 writes (an empty string is its NUL), but unambiguous
  if (n > remaining())
    throw CdrError(std::string(what) + ": a string of " + std::to_string(n) + " bytes, only " +
                   std::to_string(remaining()) + " left in the message");
  const char* p = reinterpret_cast<const char*>(data_ + pos_);
  pos_ += n;
  if (p[n - 1] != '\0') throw CdrError(std::string(what) + ": a string not ended by its NUL");
  return std::string(p, n - 1);
}

std::uint32_t CdrReader::sequenceLength(std::size_t min_element_bytes, const char* what) {
  const std::uint32_t n = uint32(what);
  const std::size_t least = std::max<std::size_t>(min_element_bytes, 1);
  if (n > remaining() / least)
    throw CdrError(std::string(what) + ": a sequence of " + std::to_string(n) +
                   " elements, of at least " + std::to_string(least) + " bytes each, only " +
                   std::to_string(remaining()) + " bytes left in the message");
  return n;
}

void CdrReader::bytes(std::vector<std::uint8_t>& out, const char* what) {
  const std::uint32_t n = sequenceLength(1, what);
  out.assign(data_ + pos_, data_ + pos_ + n);
  pos_ += n;
}

}  // namespace freeinit::ros2
