#include <fcntl.h>
#include <freeinit/io/atomic_file.h>
#include <freeinit/mrpt_plugins/rawlog_index.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <ostream>
#include <sstream>
#include <stdexcept>

namespace freeinit::mrpt_plugins {
namespace {

constexpr char kMagic[8] = {'F', 'I', 'I', 'D', 'X', '0', '0', '1'};
constexpr std::size_t kFingerprintBytes = 64 * 1024;

std::uint32_t crcOf(const unsigned char* data, std::size_t n) {
  return static_cast<std::uint32_t>(crc32(0L, data, static_cast<uInt>(n)));
}

// Little-endian encoding of the index file.
class Writer {
 public:
  template <typename T>
  void put(T v) {
    for (std::size_t i = 0; i < sizeof(T); ++i)
      bytes.push_back(static_cast<char>((static_cast<std::uint64_t>(v) >> (8 * i)) & 0xff));
  }
  void putBytes(const std::vector<unsigned char>& b) { bytes.append(b.begin(), b.end()); }
  std::string bytes;
};

class Reader {
 public:
  Reader(const std::string& b, std::size_t end) : bytes_(b), end_(end) {}
  template <typename T>
  bool get(T& v) {
    if (end_ - pos_ < sizeof(T)) return false;
    std::uint64_t x = 0;
    for (std::size_t i = 0; i < sizeof(T); ++i)
      x |= static_cast<std::uint64_t>(static_cast<unsigned char>(bytes_[pos_ + i])) << (8 * i);
    pos_ += sizeof(T);
    v = static_cast<T>(x);
    return true;
  }
  bool getBytes(std::size_t n, std::vector<unsigned char>& out) {
    if (end_ - pos_ < n) return false;
    out.assign(bytes_.begin() + static_cast<std::ptrdiff_t>(pos_),
               bytes_.begin() + static_cast<std::ptrdiff_t>(pos_ + n));
    pos_ += n;
    return true;
  }
  std::size_t left() const { return end_ - pos_; }

 private:
  const std::string& bytes_;
  std::size_t end_, pos_ = sizeof(kMagic);
};

std::uint64_t fnv1a(const std::string& s) {
  std::uint64_t h = 1469598103934665603ULL;
  for (const char c : s) {
    h ^= static_cast<unsigned char>(c);
    h *= 1099511628211ULL;
  }
  return h;
}

}  // namespace

RawlogIdentity rawlogIdentity(const std::string& rawlog) {
  struct stat st {};
  if (::stat(rawlog.c_str(), &st) != 0)
    throw std::runtime_error(rawlog + ": " + std::strerror(errno));
  RawlogIdentity id;
  id.size = static_cast<std::uint64_t>(st.st_size);
  id.mtime_ns = static_cast<std::int64_t>(st.st_mtim.tv_sec) * 1000000000LL + st.st_mtim.tv_nsec;
  std::ifstream f(rawlog, std::ios::binary);
  std::vector<unsigned char> buf(kFingerprintBytes);
  const auto n = static_cast<std::size_t>(std::min<std::uint64_t>(id.size, kFingerprintBytes));
  f.read(reinterpret_cast<char*>(buf.data()), static_cast<std::streamsize>(n));
  id.head_crc = crcOf(buf.data(), static_cast<std::size_t>(f.gcount()));
  f.seekg(static_cast<std::streamoff>(id.size - n));
  f.read(reinterpret_cast<char*>(buf.data()), static_cast<std::streamsize>(n));
  id.tail_crc = crcOf(buf.data(), static_cast<std::size_t>(f.gcount()));
  if (!f) throw std::runtime_error(rawlog + ": cannot read");
  return id;
}

const AccessPoint* RawlogIndex::pointBefore(std::uint64_t offset) const {
  const auto it = std::upper_bound(points.begin(), points.end(), offset,
                                   [](std::uint64_t o, const AccessPoint& p) { return o < p.out; });
  return it == points.begin() ? nullptr : &*(it - 1);
}

std::string indexPathBeside(const std::string& rawlog) { return rawlog + ".freeinit.idx"; }

std::string indexPathInCache(const std::string& rawlog, const std::string& cache_dir) {
  namespace fs = std::filesystem;
  fs::path dir;
  if (!cache_dir.empty()) {
    dir = cache_dir;
  } else if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg != nullptr && *xdg != 0) {
    dir = fs::path(xdg) / "freeinit";
  } else if (const char* home = std::getenv("HOME"); home != nullptr && *home != 0) {
    dir = fs::path(home) / ".cache" / "freeinit";
  } else {
    dir = fs::temp_directory_path() / "freeinit-cache";
  }
  std::error_code ec;
  const fs::path abs = fs::weakly_canonical(fs::absolute(rawlog), ec);
  std::ostringstream name;
  name << fs::path(rawlog).filename().string() << "." << std::hex << std::setw(16)
       << std::setfill('0') << fnv1a(ec ? rawlog : abs.string()) << ".freeinit.idx";
  return (dir / name.str()).string();
}

std::uint64_t maxIndexBytes(const RawlogIdentity& identity) {
  // An index holds 17 bytes per record and one compressed 32 KiB window per `spacing` bytes of
  // decompressed data: on any rawlog it is far smaller than the rawlog itself (a record with a
  // timestamp compresses to more than 17 bytes).
  return identity.size + (1u << 20);
}

bool loadRawlogIndex(const std::string& path, const RawlogIdentity& identity, RawlogIndex& out) {
  // Only a regular file of a plausible size is read: a FIFO there would block the reader, a link
  // to a device or a huge file would cost its whole size in memory. O_NONBLOCK: a FIFO put there
  // after the check does not block either (the descriptor's own kind is checked below).
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return false;
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) return false;
  const auto file_bytes = static_cast<std::uint64_t>(st.st_size);
  if (file_bytes < sizeof(kMagic) + 4 || file_bytes > maxIndexBytes(identity)) return false;
  std::string bytes(static_cast<std::size_t>(file_bytes), '\0');
  std::size_t got = 0;
  while (got < bytes.size()) {
    const ssize_t n = ::read(fd, bytes.data() + got, bytes.size() - got);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;  // shorter than it said (being rewritten) or unreadable
    got += static_cast<std::size_t>(n);
  }
  if (bytes.compare(0, sizeof(kMagic), kMagic, 8) != 0) return false;
  const std::size_t body = bytes.size() - 4;
  {
    std::uint32_t crc = 0;
    for (std::size_t i = 0; i < 4; ++i)
      crc |= static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[body + i])) << (8 * i);
    if (crc != crcOf(reinterpret_cast<const unsigned char*>(bytes.data()), body)) return false;
  }
  Reader in(bytes, body);
  RawlogIndex idx;
  std::uint8_t gzip = 0, complete = 0;
  std::uint64_t n_points = 0, n_records = 0;
  if (!in.get(idx.identity.size) || !in.get(idx.identity.mtime_ns) ||
      !in.get(idx.identity.head_crc) || !in.get(idx.identity.tail_crc) || !in.get(gzip) ||
      !in.get(complete) || !in.get(idx.spacing) || !in.get(idx.covered) || !in.get(n_points))
    return false;
  if (!(idx.identity == identity)) return false;
  idx.gzip = gzip != 0;
  idx.complete = complete != 0;
  if (n_points > in.left()) return false;
  idx.points.resize(static_cast<std::size_t>(n_points));
  for (std::size_t i = 0; i < idx.points.size(); ++i) {
    AccessPoint& p = idx.points[i];
    std::uint8_t bits = 0;
    std::uint32_t raw_len = 0, comp_len = 0;
    std::vector<unsigned char> comp;
    if (!in.get(p.in) || !in.get(bits) || !in.get(p.out) || !in.get(raw_len) || !in.get(comp_len) ||
        raw_len > 32768 || !in.getBytes(comp_len, comp))
      return false;
    // Validated against the recording: inside the file, in stream order.
    if (bits > 7 || p.in > identity.size || (i > 0 && !(p.out > idx.points[i - 1].out)))
      return false;
    p.bits = bits;
    p.window.resize(raw_len);
    uLongf len = raw_len;
    if (raw_len > 0 &&
        (uncompress(p.window.data(), &len, comp.data(), comp_len) != Z_OK || len != raw_len))
      return false;
  }
  if (!in.get(n_records) || n_records > in.left()) return false;
  idx.records.resize(static_cast<std::size_t>(n_records));
  for (std::size_t i = 0; i < idx.records.size(); ++i) {
    IndexedRecord& rec = idx.records[i];
    if (!in.get(rec.offset) || !in.get(rec.ticks) || !in.get(rec.kind)) return false;
    if (rec.kind > IndexedRecord::kAction || rec.offset >= idx.covered ||
        (i > 0 && !(rec.offset > idx.records[i - 1].offset)))
      return false;
  }
  if (in.left() != 0) return false;
  out = std::move(idx);
  return true;
}

void saveRawlogIndex(const std::string& path, const RawlogIndex& index) {
  // Something else under the index's name (a link, a FIFO, a device, a folder) was not written
  // here (an index is a regular file): it is not ours to replace.
  struct stat st {};
  if (::lstat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode))
    throw std::runtime_error(path + ": exists and is not a regular file; not replaced");
  Writer w;
  w.bytes.assign(kMagic, sizeof(kMagic));
  w.put(index.identity.size);
  w.put(index.identity.mtime_ns);
  w.put(index.identity.head_crc);
  w.put(index.identity.tail_crc);
  w.put(static_cast<std::uint8_t>(index.gzip ? 1 : 0));
  w.put(static_cast<std::uint8_t>(index.complete ? 1 : 0));
  w.put(index.spacing);
  w.put(index.covered);
  w.put(static_cast<std::uint64_t>(index.points.size()));
  for (const auto& p : index.points) {
    std::vector<unsigned char> comp(compressBound(static_cast<uLong>(p.window.size())));
    uLongf len = static_cast<uLongf>(comp.size());
    if (compress2(comp.data(), &len, p.window.data(), static_cast<uLong>(p.window.size()),
                  Z_BEST_SPEED) != Z_OK)
      throw std::runtime_error(path + ": cannot compress an access point");
    comp.resize(len);
    w.put(p.in);
    w.put(static_cast<std::uint8_t>(p.bits));
    w.put(p.out);
    w.put(static_cast<std::uint32_t>(p.window.size()));
    w.put(static_cast<std::uint32_t>(comp.size()));
    w.putBytes(comp);
  }
  w.put(static_cast<std::uint64_t>(index.records.size()));
  for (const auto& rec : index.records) {
    w.put(rec.offset);
    w.put(rec.ticks);
    w.put(rec.kind);
  }
  w.put(crcOf(reinterpret_cast<const unsigned char*>(w.bytes.data()), w.bytes.size()));
  if (const auto dir = std::filesystem::path(path).parent_path(); !dir.empty())
    std::filesystem::create_directories(dir);
  writeFileAtomically(
      path,
      [&](std::ostream& o) {
        o.write(w.bytes.data(), static_cast<std::streamsize>(w.bytes.size()));
      },
      true);
}

}  // namespace freeinit::mrpt_plugins
