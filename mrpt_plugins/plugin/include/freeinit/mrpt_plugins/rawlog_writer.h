// Writes a typed rawlog as freeinit-sim does and the freeinit app reads it: CObservationIMU and
// CObservationPointCloud (a CPointsMapDoppler, sensorPose = the extrinsics) in the order given,
// or any observation as it is, gz-compressed, into "<path>.tmp", renamed onto the path by
// commit(). A writer destroyed without commit() (an exception on the way) removes its temporary,
// and so does a commit() whose final flush fails: the rawlog is complete or absent. A recording
// (keepPartial()) is never removed: what was written is renamed onto the path in every case, and
// each of its records goes to the file whole as it is written, so that when a write fails (a full
// disk) the file is cut back to the end of the last whole record and closed there: it reads
// without error up to that record (records()). Write errors name the file and the system's reason
// ("No space left on device").
#pragma once

#include <freeinit/types.h>

#include <cstddef>
#include <memory>
#include <string>

namespace mrpt::obs {
class CObservation;
}
namespace mrpt::serialization {
class CSerializable;
}

namespace freeinit::mrpt_plugins {

class RawlogWriter {
 public:
  /// `extrinsics` and the labels are only used by the typed write()s.
  explicit RawlogWriter(std::string path, const Extrinsics& extrinsics = {},
                        std::string imu_label = "IMU", std::string lidar_label = "LIDAR");
  ~RawlogWriter();
  RawlogWriter(const RawlogWriter&) = delete;
  RawlogWriter& operator=(const RawlogWriter&) = delete;

  void write(const ImuSample& s);
  void write(const LidarFrame& f);
  /// Any observation, serialized as it is (counted as IMU / frame record by its class).
  void write(const mrpt::obs::CObservation& obs);
  /// Any object (e.g. a CSimpleMap: a .simplemap is a gz archive of one); not counted by class.
  void writeObject(const mrpt::serialization::CSerializable& obj);
  /// A recording (call it before the first write): each record is flushed to the file whole as
  /// it is written; what was written is kept (renamed onto the path) even without commit() or
  /// when a write fails, cut back to the last whole record and readable up to it.
  void keepPartial();
  /// Closes the file and renames it onto the path. Throws std::runtime_error on I/O errors
  /// (including a failed final flush), removing the temporary instead of renaming it (a
  /// recording: keeping it, see keepPartial()).
  void commit();

  /// Records written whole (with keepPartial(): those the file holds after a failed write).
  std::size_t records() const { return records_; }
  /// Why a write failed, the system's reason ("No space left on device"); "" if none did.
  std::string error() const;
  std::size_t imuRecords() const { return imu_; }
  std::size_t frameRecords() const { return frames_; }
  const std::string& path() const { return path_; }

 private:
  struct Stream;
  std::string path_;
  Extrinsics extrinsics_;
  std::string imu_label_, lidar_label_;
  std::unique_ptr<Stream> stream_;
  std::size_t records_ = 0, imu_ = 0, frames_ = 0;
  bool keep_partial_ = false;
  std::string error_;  ///< error() once the file is closed
};

/// "dir/name" for "dir/name.rawlog" (the path itself otherwise): the stem of the files written
/// beside a rawlog (<stem>.truth.csv, <stem>.extrinsics.ini).
std::string rawlogStem(const std::string& rawlog_path);

/// "<stem>.extrinsics.ini": an [extrinsics] section with R_bl (row-major) and p_bl that the app's
/// INI loader reads; `comment` becomes its first line. Written atomically.
void writeExtrinsicsIni(const std::string& path, const Extrinsics& e, const std::string& comment);

}  // namespace freeinit::mrpt_plugins
