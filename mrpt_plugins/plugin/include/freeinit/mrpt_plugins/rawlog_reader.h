// Reading rawlogs record by record without MRPT's silent truncation: stock tools stop quietly at
// the first object whose class is not registered (or at a cut-off file) and still succeed. This
// reader streams the file (gzip or plain), deserializes one top-level record at a time and
// requires the data to end exactly at the end of a record and of the gzip stream; anything else
// is an error naming the file and the record index. Memory is that of one record, and a record
// may allocate no more than its budget (setMaxRecordBytes, read_budget.h): what the rest of the
// file can hold, at most 256 MB.
//
// Seeking: rawlog_index.h. A reader loads the rawlog's index when there is one, extends it as it
// reads past what it covers, and saveIndex() writes it for rawlogs large enough to need it.
#pragma once

#include <freeinit/mrpt_plugins/rawlog_index.h>
#include <mrpt/obs/CObservation.h>
#include <mrpt/serialization/CSerializable.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace freeinit::mrpt_plugins {

/// A bad input file: the message names the file, the record index and what is wrong.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The gzip stream's checksum (CRC-32 or length, at the end of the stream) does not match the
/// data: a byte is wrong somewhere in it, so every record read from it is suspect, not only the
/// one where it was found.
class StreamIntegrityError : public InputError {
 public:
  using InputError::InputError;
};

/// Where a reader keeps a rawlog's seek index and when it writes one.
struct RawlogIndexPolicy {
  bool use = true;                           ///< read an index, write a new or longer one
  std::uint64_t min_file_bytes = 64u << 20;  ///< [bytes] only for rawlogs at least this large
  std::string cache_dir;  ///< when the rawlog's folder is not writable ("" = the user's cache)
  std::uint64_t spacing = RawlogIndex::kDefaultSpacing;  ///< [bytes] of a new index
};

/// One top-level record of a rawlog.
struct RawlogObject {
  std::size_t index = 0;    ///< record number, from 0
  std::optional<double> t;  ///< [UNIX s] its timestamp (a sensory frame: its latest), if any
  mrpt::serialization::CSerializable::Ptr object;
};

/// What a reader's progress (RawlogReader::bytesRead of fileBytes) counts: `unit` once the counts
/// are divided by `scale` (a rawlog: its bytes, shown in MB).
struct ProgressUnit {
  std::string unit = "MB";
  double scale = 1e6;
};

/// Records that come from another kind of recording, converted as they are read (a ROS bag read
/// straight in: app_support/recording_source.h). A RawlogReader made with one delegates to it.
class RecordSource {
 public:
  virtual ~RecordSource() = default;
  /// As RawlogReader::next, seekToTime and firstTime; records numbered from 0.
  virtual bool next(RawlogObject& out) = 0;
  virtual bool seekToTime(double t) = 0;
  virtual std::optional<double> firstTime() = 0;
  virtual std::uint64_t size() const = 0;         ///< progress: the whole (e.g. bytes)
  virtual std::uint64_t position() const = 0;     ///< progress: done so far, in the same unit
  virtual ProgressUnit progressUnit() const = 0;  ///< what size() and position() count
  virtual std::size_t recordsRead() const = 0;
  virtual std::size_t nextRecord() const = 0;
  virtual bool atEnd() const = 0;
};

class RawlogReader {
 public:
  /// Opens the rawlog (registering the classes first) and loads its index if it has a valid one.
  /// Throws InputError if the file is missing, empty or cannot be opened.
  explicit RawlogReader(std::string path, RawlogIndexPolicy policy = {});
  /// Reads the records of `source` (named `path` in messages): no index, no salvage, no record
  /// budget (the source bounds what it reads).
  RawlogReader(std::string path, std::unique_ptr<RecordSource> source);
  ~RawlogReader();
  RawlogReader(const RawlogReader&) = delete;
  RawlogReader& operator=(const RawlogReader&) = delete;

  const std::string& path() const;

  /// The next record; false at the end of the data, which must be the end of a record and of
  /// the gzip stream. Throws InputError naming the file and the record on a truncated file,
  /// corrupt data or a class that is not registered.
  bool next(RawlogObject& out);

  /// Positions the reader so that next() returns the first record from the current one on whose
  /// timestamp is >= t [UNIX s]. Records the index covers are skipped without decompressing more
  /// than the index's spacing or deserializing anything; beyond it they are read and dropped.
  /// False if no later record has such a timestamp (the reader is then at the end).
  bool seekToTime(double t);

  /// Timestamp of the first record that has one (read if the index does not know it).
  std::optional<double> firstTime();

  std::uint64_t fileBytes() const;
  std::uint64_t bytesRead() const;  ///< [bytes] of the file consumed so far (progress)
  /// What fileBytes and bytesRead count: bytes for a rawlog, the source's unit for another
  /// recording (a ROS recording: its log time).
  ProgressUnit progressUnit() const;
  std::size_t recordsDeserialized() const;
  std::size_t nextRecord() const;  ///< number of the record next() returns
  bool atEnd() const;              ///< next() returned false: the whole file was read
  bool indexLoaded() const;        ///< a valid index was found when opening
  const RawlogIndex& index() const;

  /// Most one record may allocate while it is deserialized (read_budget.h; 256 MB by default).
  /// The budget of a record is also bounded by what the rest of the file can hold; a record
  /// over it is an error naming the record ("a corrupt length or count").
  void setMaxRecordBytes(std::size_t bytes);

  /// Salvage mode, for a file cut short (a power loss while recording): next() returns false at
  /// the first record that cannot be read whole (the file ends inside it, or the data are
  /// corrupt from there on) instead of throwing; salvageStop() then says where and why.
  void setSalvage(bool on);
  /// In salvage mode, after next() returned false on a bad tail: "<file>: read up to record
  /// N-1, the last whole one; record N (byte B of the decompressed stream, byte C of the file):
  /// why" ("" when the file ended cleanly).
  const std::string& salvageStop() const;

  /// Writes the index if it grew and the policy allows it, beside the rawlog or else in the
  /// cache folder. Returns the path written, or "" (with the reason in `why` if it failed).
  std::string saveIndex(std::string* why = nullptr);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// One observation and the index of the top-level rawlog record it came from.
struct RawlogRecord {
  std::size_t index = 0;
  mrpt::obs::CObservation::Ptr obs;
};

/// Every observation of a rawlog in either format (observations only, or CSensoryFrame /
/// CActionCollection: sensory frames are flattened, actions skipped), through RawlogReader.
/// For tools and tests; the apps read through the ingest path (ingest.h). Throws InputError as
/// RawlogReader does, and for a record of a class that is neither.
std::vector<RawlogRecord> readRawlog(const std::string& path);

}  // namespace freeinit::mrpt_plugins
