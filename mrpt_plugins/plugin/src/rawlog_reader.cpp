#include <freeinit/mrpt_plugins/rawlog_reader.h>
#include <freeinit/mrpt_plugins/read_budget.h>
#include <freeinit/mrpt_plugins/register.h>
#include <mrpt/core/Clock.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CObservationIMU.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/serialization/CArchive.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <iomanip>
#include <limits>
#include <sstream>

#include "gz_input.h"

namespace freeinit::mrpt_plugins {
namespace {

constexpr std::int64_t kNoTime = std::numeric_limits<std::int64_t>::min();
// A record's budget from what the rest of the file can hold: objects take more memory than their
// serialized bytes (a CObservationIMU of ~300 bytes is a ~600-byte object with its shared_ptr),
// and a small file's records get a few MB whatever.
constexpr std::size_t kBudgetFactor = 16;
constexpr std::size_t kBudgetSlack = std::size_t{4} << 20;

std::string megabytes(std::size_t bytes) {
  std::ostringstream os;
  const double mb = static_cast<double>(bytes) / 1e6;
  os << std::fixed << std::setprecision(mb < 10 ? 1 : 0);
  if (mb >= 1000)
    os << std::setprecision(1) << mb / 1e3 << " GB";
  else
    os << mb << " MB";
  return os.str();
}

double ticksToUnix(std::int64_t ticks) {
  return mrpt::Clock::toDouble(mrpt::Clock::time_point(mrpt::Clock::duration(ticks)));
}

std::int64_t ticksOf(const mrpt::obs::CObservation& o) {
  if (o.timestamp == INVALID_TIMESTAMP) return kNoTime;
  return static_cast<std::int64_t>(o.timestamp.time_since_epoch().count());
}

/// The index entry of a deserialized record (offset set by the caller).
IndexedRecord describe(const mrpt::serialization::CSerializable& obj) {
  IndexedRecord r;
  r.ticks = kNoTime;
  if (const auto* o = dynamic_cast<const mrpt::obs::CObservation*>(&obj)) {
    r.ticks = ticksOf(*o);
    r.kind = dynamic_cast<const mrpt::obs::CObservationIMU*>(o) != nullptr ? IndexedRecord::kImu
             : dynamic_cast<const mrpt::obs::CObservationPointCloud*>(o) != nullptr
                 ? IndexedRecord::kPointCloud
                 : IndexedRecord::kObservation;
  } else if (const auto* sf = dynamic_cast<const mrpt::obs::CSensoryFrame*>(&obj)) {
    r.kind = IndexedRecord::kSensoryFrame;
    for (const auto& so : *sf)
      if (so) r.ticks = std::max(r.ticks, ticksOf(*so));
  } else if (dynamic_cast<const mrpt::obs::CActionCollection*>(&obj) != nullptr) {
    r.kind = IndexedRecord::kAction;
  }
  return r;
}

/// What MRPT's nested exception says, in one line: its innermost message and the objects being
/// read when it was thrown ("... (in CObservationPointCloud > CPointsMapDoppler)"). MRPT's
/// exceptions carry one "Message:" line per level and a backtrace.
/// Holds what is written to stderr (file descriptor 2) while one record is deserialized: MRPT
/// prints some errors itself (e.g. "[TRuntimeClassId::createObject] ...") before it throws, and
/// the reader's own one-line error says what is wrong. What was held is passed on to stderr
/// unless the record failed. One scratch file serves every record (rewound each time).
class StderrHold {
 public:
  StderrHold() {
    static std::FILE* scratch = std::tmpfile();
    if (scratch == nullptr) return;
    std::fflush(stderr);
    saved_ = ::dup(2);
    if (saved_ < 0) return;
    scratch_ = scratch;
    if (::ftruncate(::fileno(scratch_), 0) != 0 || ::lseek(::fileno(scratch_), 0, SEEK_SET) != 0 ||
        ::dup2(::fileno(scratch_), 2) < 0) {
      ::close(saved_);
      saved_ = -1;
    }
  }
  StderrHold(const StderrHold&) = delete;
  StderrHold& operator=(const StderrHold&) = delete;
  ~StderrHold() { release(true); }
  /// Restores stderr; with `pass`, writes what was held to it.
  void release(bool pass) {
    if (saved_ < 0) return;
    std::fflush(stderr);
    ::dup2(saved_, 2);
    ::close(saved_);
    saved_ = -1;
    if (!pass) return;
    const int fd = ::fileno(scratch_);
    const off_t size = ::lseek(fd, 0, SEEK_END);
    if (size <= 0 || ::lseek(fd, 0, SEEK_SET) != 0) return;
    char buf[4096];
    ssize_t n;
    while ((n = ::read(fd, buf, sizeof buf)) > 0)
      if (::write(2, buf, static_cast<std::size_t>(n)) < 0) break;
  }

 private:
  std::FILE* scratch_ = nullptr;
  int saved_ = -1;
};

struct MrptCause {
  std::string innermost;
  std::string objects;  ///< "CObservationPointCloud > CPointsMapDoppler"
  std::string line() const {
    return innermost + (objects.empty() ? std::string() : " (in " + objects + ")");
  }
};

MrptCause mrptCause(const std::exception& e) {
  MrptCause c;
  std::istringstream lines(e.what());
  const std::string typed = "Exception while parsing typed object '";
  for (std::string l; std::getline(lines, l);) {
    if (l.rfind("Message:", 0) != 0) continue;
    l.erase(0, l.find_first_not_of(' ', 8));
    while (!l.empty() && (l.back() == '\r' || l.back() == ' ')) l.pop_back();
    if (l.rfind(typed, 0) == 0) {
      std::string cls = l.substr(typed.size(), l.find('\'', typed.size()) - typed.size());
      if (const auto colon = cls.rfind("::"); colon != std::string::npos) cls.erase(0, colon + 2);
      c.objects += (c.objects.empty() ? "" : " > ") + cls;
    } else {
      c.innermost = l;
    }
  }
  if (c.innermost.empty() && c.objects.empty()) c.innermost = e.what();
  if (const auto nl = c.innermost.find('\n'); nl != std::string::npos) c.innermost.resize(nl);
  return c;
}

}  // namespace

struct RawlogReader::Impl {
  std::string path;
  std::unique_ptr<RecordSource> source;  ///< not a rawlog: everything from there
  RawlogIndexPolicy policy;
  detail::GzInput in;
  std::unique_ptr<mrpt::serialization::CArchive> archive;
  RawlogIndex index;
  bool index_loaded = false;
  std::string index_from;  ///< where the index was loaded from ("" if built here)
  std::size_t initial_records = 0, initial_points = 0;
  bool initial_complete = false;
  std::size_t next = 0;                 ///< number of the record at the stream position
  std::optional<RawlogObject> pending;  ///< read ahead by seekToTime / firstTime
  std::size_t deserialized = 0;
  bool at_end = false;
  bool salvage = false;
  std::string salvage_stop;
  std::size_t max_record_bytes = std::size_t{256} << 20;
  std::uint64_t failed_at = 0;  ///< where the last failure was, in the decompressed stream
  std::string failure;          ///< what it was

  std::string at(std::size_t record) const {
    return path + ": record " + std::to_string(record) + ": ";
  }

  /// readOne() in salvage mode: a bad tail ends the data.
  bool readOne(RawlogObject& out) {
    if (!salvage) return readOneStrict(out);
    try {
      return readOneStrict(out);
    } catch (const StreamIntegrityError&) {
      throw;  // not a file cut short: what was read is suspect
    } catch (const InputError&) {
      if (next == 0) throw;  // nothing whole to salvage
      salvage_stop = path + ": read up to record " + std::to_string(next - 1) +
                     ", the last whole one; record " + std::to_string(next) + " (byte " +
                     std::to_string(failed_at) + " of the decompressed stream, about byte " +
                     std::to_string(in.compressedPosition()) + " of the file): " + failure;
      at_end = true;
      return false;
    }
  }

  /// Throws InputError "<file>: record N: <why> (byte B of the decompressed stream)", keeping
  /// why and B for salvage.
  /// The records before the current one, for messages: "records 0..N are whole".
  std::string wholeRecords() const {
    if (next == 0) return "no record before it";
    return next == 1 ? "record 0 is whole"
                     : "records 0.." + std::to_string(next - 1) + " are whole";
  }

  [[noreturn]] void fail(std::uint64_t start, std::string why) {
    failed_at = start;
    failure = std::move(why);
    throw InputError(at(next) + failure + " (byte " + std::to_string(start) +
                     " of the decompressed stream)");
  }

  bool readOneStrict(RawlogObject& out) {
    const std::uint64_t start = in.getPosition();
    if (in.atEnd()) {
      if (in.integrityFailed())
        throw StreamIntegrityError(path + ": " + in.error() + " (" +
                                   (next == 0
                                        ? std::string("no record read")
                                        : "records 0.." + std::to_string(next - 1) + " read") +
                                   ")");
      if (!in.error().empty()) fail(start, "cannot be read: " + in.error());
      if (in.truncated())
        fail(start,
             "the file ends inside the gzip stream (truncated file; " + wholeRecords() + ")");
      if (next == 0)
        throw InputError(
            path + ": no rawlog record in the file (" +
            (in.gzip() ? "an empty gzip stream" : "no data") +
            "; an MRPT tool that did not load the freeinit plugin writes such a file "
            "from a rawlog with Doppler clouds: give it -p libfreeinit_mrpt_plugins.so)");
      if (next == index.records.size()) index.complete = true;
      at_end = true;
      return false;
    }
    // What this record may allocate: a few times what the rest of the file can hold (objects
    // take more memory than their bytes), at most max_record_bytes.
    const std::uint64_t bound = in.remainingBound();
    const std::uint64_t file_budget =
        bound < (std::numeric_limits<std::uint64_t>::max() - kBudgetSlack) / kBudgetFactor
            ? bound * kBudgetFactor + kBudgetSlack
            : std::numeric_limits<std::uint64_t>::max();
    const bool by_file = file_budget < max_record_bytes;
    const std::size_t budget = by_file ? static_cast<std::size_t>(file_budget) : max_record_bytes;
    mrpt::serialization::CSerializable::Ptr obj;
    std::exception_ptr error;
    std::size_t refused = 0, charged = 0;
    {
      StderrHold hold;
      {
        ReadBudget guard(budget);
        try {
          obj = archive->ReadObject();
        } catch (...) {
          error = std::current_exception();
        }
        refused = guard.refused();
        charged = guard.chargedBeforeRefusal();
      }
      hold.release(!error && refused == 0);
    }
    if (refused > 0) {
      const std::string asked =
          megabytes(refused) + (charged > 0
                                    ? " on top of the " + megabytes(charged) + " it had allocated"
                                    : std::string());
      if (by_file)
        fail(start, "cannot be read: it would allocate " + asked +
                        ", more than the rest of the file can hold: a corrupt length or count");
      fail(start, "cannot be read: it would allocate " + asked + ", more than the " +
                      megabytes(max_record_bytes) +
                      " a record may take ([input] max_record_mb): a corrupt length or count, "
                      "or a record larger than that key allows");
    }
    if (error) {
      try {
        std::rethrow_exception(error);
      } catch (const std::bad_alloc&) {
        fail(start, "cannot be read: out of memory while reading it (a corrupt length or count)");
      } catch (const std::exception& e) {
        if (!in.error().empty()) fail(start, "cannot be read: " + in.error());
        if (in.atEnd())
          fail(start,
               "the file ends inside this record (truncated file, or a corrupt length or "
               "count; " +
                   wholeRecords() + ")");
        const MrptCause cause = mrptCause(e);
        if (cause.innermost.find("not registered") != std::string::npos)
          fail(start,
               "cannot be read: " + cause.line() +
                   " (rawlogs with Doppler clouds need the plugin libfreeinit_mrpt_plugins.so)");
        if (cause.innermost.find("Cannot read requested number of bytes") != std::string::npos)
          fail(start,
               "cannot be read: corrupted data (a length or count beyond the record's "
               "data; " +
                   cause.line() + ")");
        fail(start, "cannot be read: corrupted data: " + cause.line());
      } catch (...) {
        fail(start, "cannot be read: corrupted data");
      }
    }
    if (!obj) throw InputError(at(next) + "null object");
    IndexedRecord entry = describe(*obj);
    entry.offset = start;
    if (next == index.records.size()) {
      index.records.push_back(entry);
      index.covered = in.getPosition();
    }
    out.index = next++;
    out.object = std::move(obj);
    out.t.reset();
    if (entry.ticks != kNoTime) out.t = ticksToUnix(entry.ticks);
    ++deserialized;
    return true;
  }

  /// Moves the stream to `offset` of the decompressed data, where record `record` starts.
  void seekTo(std::uint64_t offset, std::size_t record) {
    pending.reset();
    at_end = false;
    const std::uint64_t pos = in.getPosition();
    bool ok;
    if (!in.gzip()) {
      AccessPoint p;
      p.out = offset;
      in.resume(p);
      ok = true;
    } else if (offset >= pos && offset - pos <= index.spacing) {
      ok = in.discard(offset - pos);
    } else if (const AccessPoint* p = index.pointBefore(offset);
               p != nullptr && (p->out > pos || offset < pos)) {
      in.resume(*p);
      ok = in.discard(offset - p->out);
    } else if (offset < pos) {
      in.rewind();
      ok = in.discard(offset);
    } else {
      ok = in.discard(offset - pos);
    }
    if (!ok)
      throw InputError(path + ": the data end before record " + std::to_string(record) +
                       " that its index lists (a stale index: delete it)");
    next = record;
  }
};

RawlogReader::RawlogReader(std::string path, RawlogIndexPolicy policy)
    : impl_(std::make_unique<Impl>()) {
  registerClasses();
  auto& m = *impl_;
  m.path = std::move(path);
  m.policy = std::move(policy);
  std::error_code ec;
  if (std::filesystem::is_directory(m.path, ec))
    throw InputError(m.path + ": is a folder, not a rawlog file");
  if (!std::filesystem::exists(m.path, ec)) throw InputError(m.path + ": file not found");
  if (!std::filesystem::is_regular_file(m.path, ec))
    throw InputError(m.path + ": not a regular file (a rawlog is read from a file)");
  try {
    m.in.open(m.path);
  } catch (const std::exception& e) {
    throw InputError(m.path + ": cannot open: " + e.what());
  }
  if (m.in.fileBytes() == 0) throw InputError(m.path + ": empty file (0 bytes, no rawlog records)");
  if (m.policy.use) {
    try {
      const RawlogIdentity id = rawlogIdentity(m.path);
      for (const auto& candidate :
           {indexPathBeside(m.path), indexPathInCache(m.path, m.policy.cache_dir)}) {
        if (loadRawlogIndex(candidate, id, m.index) && m.index.gzip == m.in.gzip()) {
          m.index_loaded = true;
          m.index_from = candidate;
          break;
        }
      }
      if (!m.index_loaded) {
        m.index = RawlogIndex{};
        m.index.identity = id;
        m.index.gzip = m.in.gzip();
        m.index.spacing = std::max<std::uint64_t>(m.policy.spacing, 2 * detail::GzInput::kWindow);
      }
    } catch (const std::exception&) {
      m.policy.use = false;  // the index is an optimization: without it the reader still works
    }
  }
  m.initial_records = m.index.records.size();
  m.initial_points = m.index.points.size();
  m.initial_complete = m.index.complete;
  if (m.in.gzip() && m.policy.use) m.in.recordAccessPoints(&m.index.points, m.index.spacing);
  m.archive = mrpt::serialization::archiveUniquePtrFrom(m.in);
}

RawlogReader::RawlogReader(std::string path, std::unique_ptr<RecordSource> source)
    : impl_(std::make_unique<Impl>()) {
  registerClasses();
  impl_->path = std::move(path);
  impl_->source = std::move(source);
  impl_->policy.use = false;
}

RawlogReader::~RawlogReader() = default;

const std::string& RawlogReader::path() const { return impl_->path; }

bool RawlogReader::next(RawlogObject& out) {
  auto& m = *impl_;
  if (m.source) return m.source->next(out);
  if (m.pending) {
    out = std::move(*m.pending);
    m.pending.reset();
    return true;
  }
  if (m.at_end) return false;
  return m.readOne(out);
}

bool RawlogReader::seekToTime(double t) {
  auto& m = *impl_;
  if (m.source) return m.source->seekToTime(t);
  if (m.pending) {
    if (m.pending->t && *m.pending->t >= t) return true;
    m.pending.reset();
  }
  if (m.at_end) return false;
  // Within the index: jump.
  for (std::size_t r = m.next; r < m.index.records.size(); ++r) {
    const auto& e = m.index.records[r];
    if (e.ticks == kNoTime || !(ticksToUnix(e.ticks) >= t)) continue;
    if (r != m.next) m.seekTo(e.offset, r);
    return true;
  }
  if (m.index.complete) {
    m.at_end = true;
    return false;
  }
  // Beyond it: from its end, record by record.
  if (m.next < m.index.records.size()) m.seekTo(m.index.covered, m.index.records.size());
  RawlogObject rec;
  while (m.readOne(rec)) {
    if (rec.t && *rec.t >= t) {
      m.pending = std::move(rec);
      return true;
    }
  }
  return false;
}

std::optional<double> RawlogReader::firstTime() {
  auto& m = *impl_;
  if (m.source) return m.source->firstTime();
  for (const auto& e : m.index.records)
    if (e.ticks != kNoTime) return ticksToUnix(e.ticks);
  if (m.pending && m.pending->t) return m.pending->t;
  if (m.next != 0 || m.pending) return std::nullopt;  // only asked before reading anything
  RawlogObject rec;
  while (m.readOne(rec)) {
    if (rec.t) {
      const double t = *rec.t;
      m.pending = std::move(rec);
      return t;
    }
  }
  return std::nullopt;
}

void RawlogReader::setSalvage(bool on) { impl_->salvage = on; }
void RawlogReader::setMaxRecordBytes(std::size_t bytes) { impl_->max_record_bytes = bytes; }
const std::string& RawlogReader::salvageStop() const { return impl_->salvage_stop; }

std::uint64_t RawlogReader::fileBytes() const {
  return impl_->source ? impl_->source->size() : impl_->in.fileBytes();
}
ProgressUnit RawlogReader::progressUnit() const {
  return impl_->source ? impl_->source->progressUnit() : ProgressUnit{};
}
std::uint64_t RawlogReader::bytesRead() const {
  return impl_->source ? impl_->source->position() : impl_->in.compressedPosition();
}
std::size_t RawlogReader::recordsDeserialized() const {
  return impl_->source ? impl_->source->recordsRead() : impl_->deserialized;
}
std::size_t RawlogReader::nextRecord() const {
  if (impl_->source) return impl_->source->nextRecord();
  return impl_->pending ? impl_->pending->index : impl_->next;
}
bool RawlogReader::atEnd() const {
  return impl_->source ? impl_->source->atEnd() : impl_->at_end && !impl_->pending;
}
bool RawlogReader::indexLoaded() const { return impl_->index_loaded; }
const RawlogIndex& RawlogReader::index() const { return impl_->index; }

std::string RawlogReader::saveIndex(std::string* why) {
  auto& m = *impl_;
  if (m.source || !m.policy.use || m.in.fileBytes() < m.policy.min_file_bytes) return "";
  const bool grew = m.index.records.size() > m.initial_records ||
                    m.index.points.size() > m.initial_points ||
                    m.index.complete != m.initial_complete;
  if (!grew) return "";
  std::vector<std::string> places = {indexPathBeside(m.path),
                                     indexPathInCache(m.path, m.policy.cache_dir)};
  if (!m.index_from.empty() && m.index_from != places.front()) places = {m.index_from};
  std::string errors;
  for (const auto& p : places) {
    try {
      saveRawlogIndex(p, m.index);
      m.initial_records = m.index.records.size();
      m.initial_points = m.index.points.size();
      m.initial_complete = m.index.complete;
      return p;
    } catch (const std::exception& e) {
      errors += (errors.empty() ? "" : "; ") + std::string(e.what());
    }
  }
  if (why != nullptr) *why = errors;
  return "";
}

std::vector<RawlogRecord> readRawlog(const std::string& path) {
  RawlogIndexPolicy no_index;
  no_index.use = false;
  RawlogReader reader(path, no_index);
  std::vector<RawlogRecord> out;
  RawlogObject rec;
  while (reader.next(rec)) {
    if (auto o = std::dynamic_pointer_cast<mrpt::obs::CObservation>(rec.object)) {
      out.push_back({rec.index, o});
    } else if (auto sf = std::dynamic_pointer_cast<mrpt::obs::CSensoryFrame>(rec.object)) {
      for (const auto& so : *sf) out.push_back({rec.index, so});
    } else if (!std::dynamic_pointer_cast<mrpt::obs::CActionCollection>(rec.object)) {
      throw InputError(path + ": record " + std::to_string(rec.index) + ": unexpected class " +
                       rec.object->GetRuntimeClass()->className + " in a rawlog");
    }
  }
  return out;
}

}  // namespace freeinit::mrpt_plugins
