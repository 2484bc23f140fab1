#include <freeinit/mrpt/RawlogWriter.h>
#include <freeinit/mrpt/conversions.h>
#include <freeinit/mrpt/output_writers.h>
#include <freeinit/mrpt/register.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/serialization/CArchive.h>

#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <ostream>
#include <stdexcept>
#include <utility>

namespace freeinit::mrpt_glue {

struct RawlogWriter::Stream {
  mrpt::io::CFileGZOutputStream file;
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
    throw std::runtime_error(path_ + ": cannot create " + path_ + ".tmp");
  stream_->archive = mrpt::serialization::archiveUniquePtrFrom(stream_->file);
}

RawlogWriter::~RawlogWriter() {
  if (!stream_) return;
  stream_->archive.reset();
  stream_->file.close();
  std::remove((path_ + ".tmp").c_str());
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

void RawlogWriter::commit() {
  if (!stream_) throw std::logic_error(path_ + ": committed twice");
  stream_->archive.reset();
  stream_->file.close();
  stream_.reset();
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

}  // namespace freeinit::mrpt_glue
