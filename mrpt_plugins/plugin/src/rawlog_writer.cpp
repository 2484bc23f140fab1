#include <freeinit/io/atomic_file.h>
#include <freeinit/mrpt_plugins/conversions.h>
#include <freeinit/mrpt_plugins/rawlog_writer.h>
#include <freeinit/mrpt_plugins/register.h>
#include <mrpt/io/CStream.h>
#include <mrpt/obs/CObservation.h>
#include <mrpt/obs/CObservationIMU.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/serialization/CArchive.h>
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
  /// True if everything written reached the file (else error() says why).
  bool close() {
    if (file_ == nullptr) return false;
    errno = 0;
    const int rc = gzclose(file_);
    file_ = nullptr;
    if (rc != Z_OK && error_.empty())
      error_ =
          rc == Z_ERRNO && errno != 0 ? std::strerror(errno) : "gzip error " + std::to_string(rc);
    return rc == Z_OK && error_.empty();
  }
  /// Why writing failed ("" if it did not), e.g. "No space left on device".
  const std::string& error() const { return error_; }
  std::size_t Write(const void* buffer, std::size_t count) override {
    if (file_ == nullptr || count == 0) return 0;
    errno = 0;
    const int n = gzwrite(file_, buffer, static_cast<unsigned>(count));
    if (n <= 0 || static_cast<std::size_t>(n) != count) {
      int zerr = Z_OK;
      const char* what = gzerror(file_, &zerr);
      if (error_.empty())
        error_ = zerr == Z_ERRNO && errno != 0 ? std::strerror(errno)
                                               : std::string(what != nullptr ? what : "error");
      // Thrown here rather than returning a short count, so that the message names the file
      // and the system's reason instead of MRPT's generic one.
      throw std::runtime_error(path_ + ": cannot write: " + error_);
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
  std::uint64_t position_() const {
    return file_ == nullptr ? 0 : static_cast<std::uint64_t>(gztell(file_));
  }
  gzFile file_ = nullptr;
  std::string path_;
  std::string error_;
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

void RawlogWriter::keepPartial() { keep_partial_ = true; }

void RawlogWriter::writeObject(const mrpt::serialization::CSerializable& obj) {
  *stream_->archive << obj;
  ++records_;
}

void RawlogWriter::write(const ImuSample& s) {
  *stream_->archive << *imuToObservation(s, imu_label_);
  ++records_;
  ++imu_;
}

void RawlogWriter::write(const LidarFrame& f) {
  *stream_->archive << *frameToObservation(f, extrinsics_, lidar_label_);
  ++records_;
  ++frames_;
}

void RawlogWriter::write(const mrpt::obs::CObservation& obs) {
  *stream_->archive << obs;
  ++records_;
  if (dynamic_cast<const mrpt::obs::CObservationIMU*>(&obs) != nullptr) ++imu_;
  if (dynamic_cast<const mrpt::obs::CObservationPointCloud*>(&obs) != nullptr) ++frames_;
}

void RawlogWriter::commit() {
  if (!stream_) throw std::logic_error(path_ + ": committed twice");
  stream_->archive.reset();
  const bool closed = stream_->file.close();
  const std::string why = stream_->file.error();
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
