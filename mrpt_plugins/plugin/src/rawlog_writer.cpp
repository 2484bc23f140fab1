#include <fcntl.h>
#include <freeinit/io/atomic_file.h>
#include <freeinit/mrpt_plugins/conversions.h>
#include <freeinit/mrpt_plugins/rawlog_writer.h>
#include <freeinit/mrpt_plugins/register.h>
#include <mrpt/io/CStream.h>
#include <mrpt/obs/CObservation.h>
#include <mrpt/obs/CObservationIMU.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/serialization/CArchive.h>
#include <unistd.h>
#include <zlib.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iomanip>
#include <ostream>
#include <stdexcept>
#include <utility>

namespace freeinit::mrpt_plugins {

namespace {

// A write-only gzip file stream whose close() reports failure (MRPT 2.5.8's CFileGZOutputStream
// ignores gzclose's result, where a full disk shows up as the last buffered block is flushed).
//
// Recording mode (wholeRecords()): every record is flushed to the file as it ends (a zlib sync
// flush: byte-aligned, the dictionary kept, a few bytes each), and the offset, CRC-32 and length
// of the data up to there are kept. When a write fails (a full disk), close() cuts the file back
// to the end of the last whole record and ends the gzip stream there (an empty final deflate
// block and the trailer, RFC 1951/1952), so that the file reads without error up to that record.
class GzFileOut : public mrpt::io::CStream {
 public:
  ~GzFileOut() override { close(); }
  bool open(const std::string& path) {
    // Level 1, as MRPT's own rawlog writer: a 60,000-point frame compresses several times faster
    // than at zlib's default level, which matters when recording a live stream.
    path_ = path;
    errno = 0;
    file_ = gzopen(path.c_str(), "wb1");
    if (file_ == nullptr) error_ = errno != 0 ? std::strerror(errno) : "cannot open";
    return file_ != nullptr;
  }
  /// Recording mode from here on (what is written so far counts as whole).
  void wholeRecords() {
    whole_records_ = true;
    endRecord();
  }
  /// The end of a record: in recording mode it goes to the file now. Throws on error.
  void endRecord() {
    if (!whole_records_ || file_ == nullptr) return;
    errno = 0;
    if (gzflush(file_, Z_SYNC_FLUSH) != Z_OK) fail();
    const z_off_t offset = gzoffset(file_);
    if (offset < 0) fail();
    good_ = {static_cast<std::uint64_t>(offset), crc_, size_};
  }
  /// True if everything written reached the file (else error() says why; in recording mode the
  /// file then ends at its last whole record, see cutShort()).
  bool close() {
    if (file_ == nullptr) return false;
    errno = 0;
    const int rc = gzclose(file_);
    file_ = nullptr;
    if (rc != Z_OK && error_.empty())
      error_ =
          rc == Z_ERRNO && errno != 0 ? std::strerror(errno) : "gzip error " + std::to_string(rc);
    if (!error_.empty() && whole_records_) endAtLastWholeRecord();
    return rc == Z_OK && error_.empty();
  }
  /// Why writing failed ("" if it did not), e.g. "No space left on device".
  const std::string& error() const { return error_; }
  /// Recording mode, after a failed write and close(): the file was cut back to its last whole
  /// record and ends properly there.
  bool cutShort() const { return cut_short_; }
  std::size_t Write(const void* buffer, std::size_t count) override {
    if (file_ == nullptr || count == 0) return 0;
    if (!error_.empty()) throw std::runtime_error(path_ + ": cannot write: " + error_);
    errno = 0;
    const int n = gzwrite(file_, buffer, static_cast<unsigned>(count));
    if (n <= 0 || static_cast<std::size_t>(n) != count) fail();
    if (whole_records_) {
      crc_ = crc32(crc_, static_cast<const Bytef*>(buffer), static_cast<uInt>(count));
      size_ += count;
    }
    return static_cast<std::size_t>(n);
  }
  std::size_t Read(void*, std::size_t) override {
    throw std::logic_error("GzFileOut is write-only");
  }
  std::uint64_t Seek(std::int64_t, CStream::TSeekOrigin) override {
    throw std::logic_error("GzFileOut cannot seek");
  }
  std::uint64_t getTotalBytesCount() const override { return position_(); }
  std::uint64_t getPosition() const override { return position_(); }

 private:
  struct WholePoint {
    std::uint64_t offset = 0;  ///< [bytes] file size up to the end of the last whole record
    uLong crc = 0;             ///< CRC-32 of the uncompressed data up to there
    std::uint64_t size = 0;    ///< [bytes] uncompressed data up to there
  };

  /// Records the reason and throws, naming the file and the system's reason rather than MRPT's
  /// generic one (a short count would make MRPT throw its own).
  [[noreturn]] void fail() {
    int zerr = Z_OK;
    const char* what = file_ != nullptr ? gzerror(file_, &zerr) : nullptr;
    if (error_.empty())
      error_ = (zerr == Z_ERRNO || what == nullptr) && errno != 0
                   ? std::strerror(errno)
                   : std::string(what != nullptr && *what != '\0' ? what : "write error");
    throw std::runtime_error(path_ + ": cannot write: " + error_);
  }

  void endAtLastWholeRecord() {
    const int fd = ::open(path_.c_str(), O_WRONLY | O_CLOEXEC);
    if (fd < 0) return;
    unsigned char end[10] = {0x03, 0x00};  // a final fixed-Huffman block holding no data
    for (int k = 0; k < 4; ++k) {
      end[2 + k] = static_cast<unsigned char>((good_.crc >> (8 * k)) & 0xff);
      end[6 + k] = static_cast<unsigned char>((good_.size >> (8 * k)) & 0xff);  // mod 2^32
    }
    const auto at = static_cast<off_t>(good_.offset);
    cut_short_ = ::ftruncate(fd, at) == 0 && ::pwrite(fd, end, sizeof(end), at) == sizeof(end);
    ::close(fd);
  }

  std::uint64_t position_() const {
    return file_ == nullptr ? 0 : static_cast<std::uint64_t>(gztell(file_));
  }
  gzFile file_ = nullptr;
  std::string path_;
  std::string error_;
  bool whole_records_ = false, cut_short_ = false;
  uLong crc_ = crc32(0L, Z_NULL, 0);
  std::uint64_t size_ = 0;
  WholePoint good_;
};

}  // namespace

struct RawlogWriter::Stream {
  GzFileOut file;
  std::unique_ptr<mrpt::serialization::CArchive> archive;
};

RawlogWriter::RawlogWriter(std::string path, const Extrinsics& extrinsics, std::string imu_label,
                           std::string lidar_label)
    : path_(std::move(path)),
      extrinsics_(extrinsics),
      imu_label_(std::move(imu_label)),
      lidar_label_(std::move(lidar_label)),
      stream_(std::make_unique<Stream>()) {
  registerClasses();
  if (const auto dir = std::filesystem::path(path_).parent_path(); !dir.empty())
    std::filesystem::create_directories(dir);
  if (!stream_->file.open(path_ + ".tmp"))
    throw std::runtime_error(path_ + ": cannot create " + path_ + ".tmp: " + stream_->file.error());
  stream_->archive = mrpt::serialization::archiveUniquePtrFrom(stream_->file);
}

RawlogWriter::~RawlogWriter() {
  if (!stream_) return;
  stream_->archive.reset();
  stream_->file.close();
  if (keep_partial_)
    std::rename((path_ + ".tmp").c_str(), path_.c_str());
  else
    std::remove((path_ + ".tmp").c_str());
}

std::string RawlogWriter::error() const { return stream_ ? stream_->file.error() : error_; }

void RawlogWriter::keepPartial() {
  keep_partial_ = true;
  stream_->file.wholeRecords();
}

void RawlogWriter::writeObject(const mrpt::serialization::CSerializable& obj) {
  *stream_->archive << obj;
  stream_->file.endRecord();
  ++records_;
}

void RawlogWriter::write(const ImuSample& s) {
  *stream_->archive << *imuToObservation(s, imu_label_);
  stream_->file.endRecord();
  ++records_;
  ++imu_;
}

void RawlogWriter::write(const LidarFrame& f) {
  *stream_->archive << *frameToObservation(f, extrinsics_, lidar_label_);
  stream_->file.endRecord();
  ++records_;
  ++frames_;
}

void RawlogWriter::write(const mrpt::obs::CObservation& obs) {
  *stream_->archive << obs;
  stream_->file.endRecord();
  ++records_;
  if (dynamic_cast<const mrpt::obs::CObservationIMU*>(&obs) != nullptr) ++imu_;
  if (dynamic_cast<const mrpt::obs::CObservationPointCloud*>(&obs) != nullptr) ++frames_;
}

void RawlogWriter::commit() {
  if (!stream_) throw std::logic_error(path_ + ": committed twice");
  stream_->archive.reset();
  const bool closed = stream_->file.close();
  const std::string why = error_ = stream_->file.error();
  stream_.reset();
  if (!closed) {
    if (keep_partial_)
      std::rename((path_ + ".tmp").c_str(), path_.c_str());
    else
      std::remove((path_ + ".tmp").c_str());
    throw std::runtime_error(path_ + ": cannot write: " + why);
  }
  std::error_code ec;
  std::filesystem::rename(path_ + ".tmp", path_, ec);
  if (ec) {
    std::remove((path_ + ".tmp").c_str());
    throw std::runtime_error(path_ + ": cannot rename the temporary file: " + ec.message());
  }
}

std::string rawlogStem(const std::string& rawlog_path) {
  const std::string ext = ".rawlog";
  if (rawlog_path.size() > ext.size() &&
      rawlog_path.compare(rawlog_path.size() - ext.size(), ext.size(), ext) == 0)
    return rawlog_path.substr(0, rawlog_path.size() - ext.size());
  return rawlog_path;
}

void writeExtrinsicsIni(const std::string& path, const Extrinsics& e, const std::string& comment) {
  writeFileAtomically(path, [&](std::ostream& o) {
    o << std::setprecision(12) << "; " << comment << "\n[extrinsics]\nR_bl = ";
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) o << e.R_bl(r, c) << (r * 3 + c < 8 ? " " : "\n");
    o << "p_bl = " << e.p_bl.x() << " " << e.p_bl.y() << " " << e.p_bl.z() << "\n";
  });
}

}  // namespace freeinit::mrpt_plugins
