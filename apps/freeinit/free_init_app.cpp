#include "free_init_app.h"

#include <freeinit/app_support/command_line.h>
#include <freeinit/app_support/file_kind.h>
#include <freeinit/app_support/ingest.h>
#include <freeinit/app_support/ingest_sources.h>
#include <freeinit/app_support/output_file_kind.h>
#include <freeinit/app_support/output_set.h>
#include <freeinit/app_support/output_writers.h>
#include <freeinit/app_support/progress_bar.h>
#include <freeinit/app_support/recording_source.h>
#include <freeinit/app_support/result_files.h>
#include <freeinit/app_support/snapshots.h>
#include <freeinit/app_support/stop_signal.h>
#include <freeinit/input_checks.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <deque>
#include <filesystem>
#include <functional>
#include <iomanip>
#include <iostream>
#include <limits>
#include <memory>
#include <ostream>
#include <sstream>

namespace freeinit::apps {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

std::string v3(const Vec3& v) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(4) << v.x() << " " << v.y() << " " << v.z();
  return os.str();
}

constexpr const char* kStateFile = "initial_state.ini";
constexpr const char* kErrorsFile = "errors_wrt_gt.ini";
constexpr const char* kConfigFile = "effective_config.ini";

/// One start's initialization, open from its start on.
struct Slot {
  std::size_t index = 0;
  double start = 0;
  std::unique_ptr<app_support::InitSession> session;
};

/// Stages one start's outputs in `set` under `prefix` ("" or "start_0012.000/").
void writeStateSet(app_support::OutputSet& set, const std::string& prefix,
                   const app_support::AppConfig& config, const InitResult& result,
                   const std::optional<app_support::TruthErrors>& errors,
                   const std::vector<app_support::TruthSample>& truth,
                   const std::string* effective) {
  if (effective != nullptr)
    set.write(prefix + kConfigFile, [&](const std::string& p) {
      writeFileAtomically(p, [&](std::ostream& o) { o << *effective; });
    });
  const app_support::StateVerdict verdict =
      app_support::verdictOf(result, config.core.doppler.doppler_sigma);
  set.write(prefix + kStateFile, [&](const std::string& p) {
    app_support::writeInitialStateIni(p, result.state, &verdict);
  });
  if (errors)
    set.write(prefix + kErrorsFile,
              [&](const std::string& p) { app_support::writeTruthErrors(p, *errors); });
  app_support::writeResultFiles(set, prefix, config.output, result, truth);
}

/// Removes the folders it holds at the end of its scope, innermost first, those that are empty
/// only: a new output folder (and its parent, when made for it) that a failed run left empty.
class EmptyFolderSweep {
 public:
  void add(const fs::path& dir) { dirs_.push_back(dir); }
  ~EmptyFolderSweep() {
    for (auto it = dirs_.rbegin(); it != dirs_.rend(); ++it) {
      std::error_code ec;
      if (fs::is_empty(*it, ec) && !ec) fs::remove(*it, ec);
    }
  }

 private:
  std::vector<fs::path> dirs_;
};

std::string localStamp() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  localtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof(buf), "%Y%m%d-%H%M%S", &tm);
  return buf;
}

/// Refuses what no run takes (std::invalid_argument): a bad --every or --start, --every with
/// --starts, arguments argumentsProblem() tells apart.
void checkParams(const FreeInitAppParams& p) {
  if (p.every < 0 || !std::isfinite(p.every)) throw std::invalid_argument("--every must be > 0");
  if (p.every > 0 && !p.starts_file.empty())
    throw std::invalid_argument("--every and --starts exclude each other");
  if (p.start && !(*p.start >= 0)) throw std::invalid_argument("--start must be >= 0");
  if (const std::string problem = p.argumentsProblem(); !problem.empty())
    throw std::invalid_argument(problem);
}

/// --every or --starts: many starts, each in its folder, with a table of them.
bool severalStarts(const FreeInitAppParams& p) { return p.every > 0 || !p.starts_file.empty(); }

/// The output folder made for this run (no --out), under `sweep` so that a failed run leaves no
/// empty folder behind (nor the root, when made for it).
std::string newOutputFolder(const FreeInitAppParams& p, EmptyFolderSweep& sweep) {
  if (!fs::exists(p.new_out_root)) sweep.add(p.new_out_root);
  const std::string dir = createNewOutputFolder(p.new_out_root, p.rawlog);
  sweep.add(dir);
  return dir;
}

/// The run's starts: --every or --starts, else the one at `from` [UNIX s] (-inf: the first
/// record). `first` [UNIX s]: the first record's stamp, known with --start and several starts.
/// Refuses (std::invalid_argument, InputError for the file) starts so close that more than
/// kMaxOpenStarts windows of `window` [s] overlap, or more than kMaxStarts in a file; sets
/// `decimals` to those of the start folders' names (folderDecimals).
StartPlan startPlan(const FreeInitAppParams& p, double from, const std::optional<double>& first,
                    double window, int& decimals) {
  decimals = 3;
  if (p.every > 0) {
    if (const std::string problem = everyProblem(p.every, window); !problem.empty())
      throw std::invalid_argument(problem);
    while (decimals < 9 && p.every < std::pow(10.0, -decimals)) ++decimals;
    return StartPlan::every(p.start ? from : *first, p.every);
  }
  if (!p.starts_file.empty()) {
    std::vector<double> t = readStartsFile(p.starts_file);
    for (double& x : t) x = startTime(x, *first);
    if (const std::string problem = startsProblem(t, window, p.starts_file); !problem.empty())
      throw mrpt_plugins::InputError(problem);
    std::vector<double> offsets = t;
    for (double& x : offsets) x -= *first;
    decimals = folderDecimals(offsets);
    return StartPlan::list(std::move(t));
  }
  return StartPlan::single(from);
}

/// At most this many errors of a failed start are named in its message (the others counted).
constexpr std::size_t kErrorsNamed = 4;

/// The result of the only start's session, with a line on what went in. Throws InputError when
/// it failed (its errors in one message, printed once, on the error stream: the first, and the
/// next ones after it up to kErrorsNamed), or why there is no window when the file ended before
/// the window closed.
const InitResult& resultOf(const app_support::InitSession& s, std::ostream& log) {
  if (s.failed()) {
    const std::vector<std::string>& errors = s.errors();
    std::string message = errors.front();
    if (errors.size() > 1) {
      message += " (and " + std::to_string(errors.size() - 1) + " more:";
      for (std::size_t i = 1; i < std::min(errors.size(), kErrorsNamed); ++i)
        message += (i == 1 ? " " : "; ") + errors[i];
      if (errors.size() > kErrorsNamed) message += "; ...";
      message += ")";
    }
    throw mrpt_plugins::InputError(message);
  }
  // The file ended before the window closed.
  if (!s.ready() || s.result().state.status == InitStatus::NotEnoughData)
    throw mrpt_plugins::InputError(s.endOfDataReason());
  log << "Input: " << s.imuCount() << " IMU samples and " << s.frameCount() << " point clouds from "
      << input::formatStamp(s.firstTime().value_or(0)) << " to "
      << input::formatStamp(s.lastTime().value_or(0)) << "\n";
  return s.result();
}

/// The state on the log: status, values, points, the verdict, warnings and, when the
/// configuration takes them from there, the extrinsics the clouds' sensorPoses give.
void printInitialState(std::ostream& log, const InitResult& result,
                       const app_support::AppConfig& config,
                       const std::optional<Extrinsics>& cloud_extrinsics) {
  const InitialState& s = result.state;
  log << "Initialization: " << toString(s.status)
      << (s.message.empty() ? "" : " (" + s.message + ")") << "\n";
  log << std::fixed << std::setprecision(6) << "  timestamp " << s.timestamp << "\n"
      << std::setprecision(4) << "  v_b  " << v3(s.v_b()) << " m/s\n  g_b  " << v3(s.g_b())
      << " m/s^2\n  b_g  " << v3(s.b_g) << " rad/s\n  b_a  " << v3(s.b_a) << " m/s^2\n"
      << std::defaultfloat << "  points: " << result.diag.points_used << " used, "
      << result.diag.points_rejected << " rejected, " << result.diag.points_skipped
      << " skipped; static start: " << (result.diag.static_start ? "yes" : "no") << "\n";
  if (s.ok())
    app_support::printVerdict(log,
                              app_support::verdictOf(result, config.core.doppler.doppler_sigma));
  for (const auto& w : s.warnings) log << "  warning: " << w << "\n";
  if (config.extrinsics.from_sensor_pose && cloud_extrinsics)
    log << "Extrinsics from sensorPose: p_bl = " << v3(cloud_extrinsics->p_bl) << " m\n";
}

/// The errors against the ground truth (from `truth_file`) on the log.
void printTruthErrors(std::ostream& log, const std::string& truth_file,
                      const app_support::TruthErrors& e) {
  log << "Errors w.r.t. ground truth (" << truth_file << "):\n"
      << "  velocity    " << e.velocity << " m/s\n"
      << "  gravity     " << e.gravity_deg << " deg\n"
      << "  gyro bias   " << e.gyro_bias << " rad/s\n"
      << "  accel bias  " << e.accel_bias << " m/s^2\n";
}

/// [s] since `t`.
double secondsSince(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

}  // namespace

std::string createNewOutputFolder(const std::string& root, const std::string& rawlog) {
  std::string stem = fs::path(rawlog).stem().string();
  if (stem.empty()) stem = "freeinit";
  const std::string base = (fs::path(root) / (stem + "." + localStamp())).string();
  std::error_code ec;
  fs::create_directories(root, ec);
  if (ec)
    throw app_support::OutputError(root + ": cannot create the output folder: " + ec.message());
  for (int n = 1; n <= 1000; ++n) {
    const std::string dir = n == 1 ? base : base + "-" + std::to_string(n);
    if (fs::exists(fs::symlink_status(dir, ec))) continue;
    if (fs::create_directory(dir, ec)) return dir;
    if (ec)
      throw app_support::OutputError(dir + ": cannot create the output folder: " + ec.message());
    // Another run took it in between: the next name.
  }
  throw app_support::OutputError(
      base + ": cannot create the output folder: 1000 folders of that name exist");
}

std::string FreeInitAppParams::argumentsProblem() const {
  // An output of an earlier run where the configuration or the recording goes.
  if (!config_file.empty())
    if (std::string p = app_support::outputGivenAsInput(
            config_file, "<config.ini>", "a configuration",
            "an INI configuration such as ini/freeinit.ini (or a run's effective_config.ini)");
        !p.empty())
      return p;
  if (std::string p = app_support::outputGivenAsInput(
          rawlog, "<input.rawlog>", "a recording",
          "the recording the run read (an MRPT .rawlog, e.g. rawlogs/dyna_01.rawlog)");
      !p.empty())
    return p;
  if (!config_file.empty()) return "";  // the configuration's and the rawlog's readers check
  const app_support::FileKind input = app_support::fileKind(rawlog);
  if (input == app_support::FileKind::Ini)
    return "missing <input.rawlog>: '" + rawlog + "' is " + app_support::describe(input) +
           " (freeinit [<config.ini>] <input.rawlog>)";
  if (input == app_support::FileKind::Text || input == app_support::FileKind::Binary)
    return "<input.rawlog> '" + rawlog + "': neither an MRPT rawlog nor a ROS recording (it is " +
           app_support::describe(input) + ")";
  return "";
}

/// What the steps of one run share.
struct FreeInitApp::Job {
  Job(Clock::time_point t0, app_support::OutputSet& outputs, std::string effective)
      : t_start(t0), set(outputs), effective_config(std::move(effective)) {}

  Clock::time_point t_start;
  app_support::OutputSet& set;
  std::string effective_config;  ///< the configuration's text, as effective_config.ini holds it
  std::unique_ptr<mrpt_plugins::RawlogReader> reader;
  std::optional<double> first;  ///< [UNIX s] the first record's stamp (with --start, many starts)
  StartPlan plan = StartPlan::single(-std::numeric_limits<double>::infinity());
  int folder_decimals = 3;                      ///< of the start folders' names (folderDecimals)
  std::vector<app_support::TruthSample> truth;  ///< from truth_file, when it is beside the rawlog
  std::string truth_file;
};

/// One pass over the records through the ingest path (ingest_sources.h) for the starts of the
/// job's plan: a session opens at each start the records reach, takes the checked items from its
/// start on and closes when its state is ready or it failed; `close` then gets it, its warnings
/// logged. With no session open the reader seeks to the next start, and the reading stops when
/// no start is left (with --check-all every record is read and checked).
class FreeInitApp::StartPass {
 public:
  /// One start's end. `at_end`: the file ended before its window closed.
  using Close = std::function<void(const Slot& slot, bool at_end)>;

  StartPass(FreeInitApp& app, Job& job, std::ostream& log, Close close)
      : app_(app),
        job_(job),
        reader_(*job.reader),
        log_(log),
        close_(std::move(close)),
        decoder_(app.config.input),
        checker_(app.config),
        bar_(log, "  reading", reader_.progressUnit().unit, app.params.progress_terminal,
             reader_.progressUnit().scale) {}

  /// Reads to the end of the file, to an unreadable record, or as far as the starts need, and
  /// closes every session: those still open fail at an unreadable record, else they finish with
  /// what the file holds.
  void read() {
    for (;;) {
      mrpt_plugins::RawlogObject rec;
      if (!nextRecord(rec)) break;
      if (app_.params.progress) bar_.update(reader_.bytesRead(), reader_.fileBytes());
      app_support::checkRecord(
          decoder_, checker_, rec, [this](const app_support::CheckedItem& c) { dispatch(c); },
          [this](const app_support::IngestItem& item) { return admit(item); });
      closeDone();
    }
    last_record_ = reader_.nextRecord();
    app_.records_read = reader_.recordsDeserialized();
    app_.read_to_end = reader_.atEnd();
    app_.salvage_stop = reader_.salvageStop();
    if (!app_.salvage_stop.empty()) app_.warn(log_, app_.salvage_stop);

    if (read_error_) {
      // Unreadable from here on: the open windows fail; what comes after is not checked.
      for (auto& s : active_) s.session->fail(*read_error_);
      if (active_.empty() && !job_.plan.peek())
        outside_.push_back(*read_error_ + "; the rest of the file was not checked");
    } else if (!stopped_early_) {
      // The end of the file: windows still open close with what is there.
      std::vector<app_support::CheckedItem> checked;
      checker_.finish(checked);
      for (const auto& c : checked) dispatch(c);
      for (auto& s : active_) s.session->finish();
    }
    for (auto& s : active_) closeSlot(s, !read_error_);
    active_.clear();
  }

  /// The reading's end on the log: the progress bar, the bad records no session took, where the
  /// reading stopped; the seek index, written when due.
  void end() {
    if (app_.params.progress)
      bar_.finish(stopped_early_ ? "(state ready: the rest of the input is not needed)" : "");
    for (const auto& w : outside_) app_.warn(log_, w);
    if (stopped_early_)
      log_ << "Read up to record " << (last_record_ == 0 ? 0 : last_record_ - 1)
           << "; the rest was not checked (use --check-all)\n";
    std::string why;
    app_.index_written = reader_.saveIndex(&why);
    if (!app_.index_written.empty()) log_ << "Seek index written to " << app_.index_written << "\n";
    if (!why.empty()) log_ << "Warning: the seek index could not be written: " << why << "\n";
  }

  /// The reader's error that ended the reading, if one did.
  const std::optional<std::string>& readError() const { return read_error_; }
  /// Throws the reader's error when it says the whole stream is suspect (its gzip checksum
  /// failed, e.g. at the end of the file with --check-all): no start's state can be trusted,
  /// whether its window was read before or not.
  void throwIfStreamSuspect() const {
    if (integrity_failed_) throw mrpt_plugins::StreamIntegrityError(*read_error_);
  }
  const app_support::RecordChecker& checker() const { return checker_; }

 private:
  /// No session open and no need to read on but for the next start.
  bool idle() const { return active_.empty() && !app_.params.check_all; }

  /// The next record to read; false at the end of the file, at an unreadable record, or when no
  /// start is left for an idle pass (stopped early unless at the end).
  bool nextRecord(mrpt_plugins::RawlogObject& rec) {
    if (idle() && !job_.plan.peek()) {
      stopped_early_ = !reader_.atEnd();
      return false;
    }
    app_support::throwIfStopRequested();
    try {
      // Idle: straight to the next start (no record at or after it: the end).
      if (idle() && !reader_.seekToTime(*job_.plan.peek())) return false;
      return reader_.next(rec);
    } catch (const mrpt_plugins::StreamIntegrityError& e) {
      read_error_ = e.what();
      integrity_failed_ = true;
      return false;
    } catch (const mrpt_plugins::InputError& e) {
      read_error_ = e.what();
      return false;
    }
  }

  /// Opens the sessions of the starts `item` reaches; false when it is not needed (idle).
  bool admit(const app_support::IngestItem& item) {
    while (std::isfinite(item.t)) {
      const auto next = job_.plan.peek();
      if (!next || item.t < *next) break;
      active_.push_back(
          {job_.plan.index(), *next,
           std::make_unique<app_support::InitSession>(app_.config, app_.params.rawlog)});
      job_.plan.pop();
    }
    return !idle();  // before the next start: not needed
  }

  /// A checked item to every open session it is at or after the start of.
  void dispatch(const app_support::CheckedItem& c) {
    bool taken = false;
    for (auto& s : active_) {
      if (s.session->done() || !(c.item.t >= s.start)) continue;
      s.session->push(c);
      taken = true;
    }
    if (!taken && !c.ok())
      outside_.push_back(app_.params.rawlog + ": record " + std::to_string(c.item.record) + ": " +
                         c.problem + " (not used: outside every initialization window)");
  }

  void closeDone() {
    for (auto it = active_.begin(); it != active_.end();) {
      if (!it->session->done()) {
        ++it;
        continue;
      }
      closeSlot(*it, false);
      it = active_.erase(it);
    }
  }

  void closeSlot(const Slot& slot, bool at_end) {
    for (const auto& w : slot.session->warnings()) app_.warn(log_, w);
    close_(slot, at_end);
  }

  FreeInitApp& app_;
  Job& job_;
  mrpt_plugins::RawlogReader& reader_;
  std::ostream& log_;
  Close close_;
  app_support::ObservationDecoder decoder_;
  app_support::RecordChecker checker_;
  app_support::ProgressBar bar_;
  std::deque<Slot> active_;
  std::vector<std::string> outside_;  ///< bad records no session took
  std::optional<std::string> read_error_;
  bool integrity_failed_ = false;  ///< read_error_ is a StreamIntegrityError
  bool stopped_early_ = false;     ///< the starts needed no more (the file goes on)
  std::size_t last_record_ = 0;
};

int FreeInitApp::run(std::ostream& log) {
  const auto t_start = Clock::now();
  checkParams(params);
  rows.clear();
  warnings.clear();
  result = InitResult{};
  errors_wrt_gt.reset();
  // A new folder for this run when none is given; removed again if the run fails.
  EmptyFolderSweep sweep;
  out_dir = params.out_dir;
  if (out_dir.empty()) out_dir = newOutputFolder(params, sweep);
  // The outputs' set: locked now, installed as a whole at the end; on any failure (an exception
  // through here) the staging folder goes and the earlier run's outputs stay as they were.
  app_support::OutputSet set(out_dir, "", app_support::folderSetOptions(), log);

  Job job(t_start, set, loadConfiguration(log));
  openRecording(job, log);
  return severalStarts(params) ? initializeAtStarts(job, log) : initializeOnce(job, log);
}

std::string FreeInitApp::loadConfiguration(std::ostream& log) {
  std::vector<std::string> notices;  // keys given under their former names
  config = params.config_file.empty() ? app_support::loadAppConfigFromText("", "the defaults")
                                      : app_support::loadAppConfig(params.config_file, &notices);
  for (const std::string& n : notices) log << n << "\n";
  std::ostringstream effective;
  app_support::dumpAppConfig(config, effective);
  if (params.echo_config)
    log << "Effective configuration ("
        << (params.config_file.empty() ? "the defaults: no configuration file" : params.config_file)
        << "):\n"
        << effective.str() << "\n";
  return effective.str();
}

void FreeInitApp::openRecording(Job& job, std::ostream& log) {
  log << "Reading " << params.rawlog << "\n";
  std::vector<std::string> input_warnings;
  job.reader = app_support::openInput(params.rawlog, config, params.index, &input_warnings);
  for (const auto& w : input_warnings) warn(log, w);
  mrpt_plugins::RawlogReader& reader = *job.reader;
  reader.setSalvage(params.salvage);
  reader.setMaxRecordBytes(static_cast<std::size_t>(config.input.max_record_mb * 1e6));
  index_used = reader.indexLoaded();
  if (index_used) log << "  seek index found (" << reader.index().records.size() << " records)\n";
  if (params.start || severalStarts(params)) {
    job.first = reader.firstTime();
    if (!job.first) throw mrpt_plugins::InputError(params.rawlog + ": no record has a timestamp");
  }
  const double from = params.start ? startTime(*params.start, *job.first)
                                   : -std::numeric_limits<double>::infinity();
  job.plan = startPlan(params, from, job.first, config.core.window.duration, job.folder_decimals);
  if (params.start)
    log << "  start at " << input::formatStamp(from) << " (" << from - *job.first
        << " s after the first record)\n";

  job.truth_file = app_support::truthPathFor(params.rawlog);
  if (fs::is_regular_file(job.truth_file)) job.truth = app_support::readTruthCsv(job.truth_file);
}

int FreeInitApp::initializeOnce(Job& job, std::ostream& log) {
  StartPass pass(*this, job, log,
                 [&](const Slot& slot, bool) { result = resultOf(*slot.session, log); });
  pass.read();
  pass.throwIfStreamSuspect();
  if (const auto start = job.plan.peek()) {
    if (pass.readError()) throw mrpt_plugins::InputError(*pass.readError());
    throw mrpt_plugins::InputError(
        params.rawlog + ": no record at or after the start " + input::formatStamp(*start) +
        (job.first ? " (" + std::to_string(*start - *job.first) + " s after the first record)"
                   : std::string()));
  }
  pass.end();

  const InitialState& s = result.state;
  printInitialState(log, result, config, pass.checker().declaredExtrinsics());
  // Ground truth, when it sits beside the rawlog.
  if (!job.truth.empty() && s.ok()) {
    errors_wrt_gt = app_support::compareWithTruth(s, job.truth);
    printTruthErrors(log, job.truth_file, *errors_wrt_gt);
  }

  // The outputs, staged, then installed as one set.
  writeStateSet(job.set, "", config, result, errors_wrt_gt, job.truth, &job.effective_config);
  job.set.commit();
  log << "Outputs in " << out_dir << " (" << std::setprecision(3) << secondsSince(job.t_start)
      << " s total)\n";
  return s.ok() ? 0 : 3;
}

int FreeInitApp::initializeAtStarts(Job& job, std::ostream& log) {
  int exit_code = 0;
  StartPass pass(*this, job, log, [&](const Slot& slot, bool at_end) {
    const app_support::InitSession& s = *slot.session;
    StartRow row =
        startRow(slot.index, slot.start, *job.first, s, at_end, job.truth, job.folder_decimals);
    if (!row.folder.empty())
      writeStateSet(job.set, row.folder + "/", config, s.result(),
                    row.truth ? std::optional(row.truth->errors) : std::nullopt, job.truth,
                    nullptr);
    printStartRow(log, row, out_dir);
    if (startFailed(row, at_end)) exit_code = 3;
    rows.push_back(std::move(row));
  });
  pass.read();
  pass.throwIfStreamSuspect();
  // Starts the file does not reach.
  const std::optional<std::string>& read_error = pass.readError();
  std::size_t k = job.plan.index();
  for (double t : job.plan.rest()) {
    rows.push_back(unreachedStartRow(k++, t, *job.first, read_error));
    if (read_error) exit_code = 3;
  }
  if (read_error && params.every > 0 && job.plan.peek())
    log << "Warning: no start from " << std::fixed << std::setprecision(3)
        << *job.plan.peek() - *job.first << std::defaultfloat << " s on: " << *read_error << "\n";
  if (const auto beyond = job.plan.beyondLimit(); beyond && !read_to_end) {
    std::ostringstream os;
    os << "--every " << params.every << ": " << kMaxStarts
       << " starts, the most one run makes; the recording goes on: run again with --start "
       << std::fixed << std::setprecision(3) << *beyond - *job.first << " for the next ones";
    warn(log, os.str());
  }
  pass.end();

  writeStartTable(job, log);
  return rows.empty() ? 3 : exit_code;
}

void FreeInitApp::writeStartTable(Job& job, std::ostream& log) {
  job.set.write(kConfigFile, [&](const std::string& p) {
    writeFileAtomically(p, [&](std::ostream& o) { o << job.effective_config; });
  });
  std::sort(rows.begin(), rows.end(),
            [](const StartRow& a, const StartRow& b) { return a.index < b.index; });
  if (std::any_of(rows.begin(), rows.end(),
                  [](const StartRow& r) { return r.state && r.state->ok(); }))
    job.set.write("starts.png", [&](const std::string& p) {
      renderStartPlot(p, rows, config.output.snapshot_width, config.output.snapshot_height);
    });
  job.set.write("starts.csv", [&](const std::string& p) { writeStartTableCsv(p, rows); });
  job.set.write("starts.md", [&](const std::string& p) {
    writeStartTableMarkdown(p, rows, params.rawlog,
                            params.command.empty() ? "freeinit" : params.command);
  });
  job.set.commit();
  std::size_t ok = 0;
  for (const auto& r : rows) ok += r.status == toString(InitStatus::Ok) ? 1 : 0;
  log << rows.size() << " start(s), " << ok << " initialized; table in "
      << (fs::path(out_dir) / "starts.md").string() << " (" << std::setprecision(3)
      << secondsSince(job.t_start) << " s total)\n";
}

void FreeInitApp::warn(std::ostream& log, const std::string& warning) {
  log << "Warning: " << warning << "\n";
  warnings.push_back(warning);
}

int FreeInitApp::main(int argc, char** argv) {
  namespace range = freeinit::config;
  app_support::CommandLine cli(
      "freeinit",
      "initial state (attitude, velocity, biases, gravity, static map) from the "
      "first instants of a Doppler LiDAR + IMU rawlog");
  const auto& ini = cli.positional("config.ini",
                                   "INI configuration file (ini/freeinit.ini documents every key); "
                                   "without it the defaults, the extrinsics from the rawlog",
                                   false);
  const auto& rawlog = cli.positional(
      "input.rawlog",
      "input rawlog, or a ROS recording read straight in (a ROS 1 bag, an MCAP file, a rosbag2 "
      "folder, a .db3; [bag_import] of the INI says how)");
  const auto& out =
      cli.text("o", "out", "output folder (its earlier outputs are replaced)", "", "DIR",
               std::string(kDefaultOutDir) +
                   "; without <config.ini> a new folder for each run, "
                   "freeinit_out/<input>.<time>");
  const auto& quiet = cli.flag("q", "quiet", "no progress bar");
  const auto& print_config =
      cli.flag("", "print-config",
               "list the effective configuration (every key with the value used) before the "
               "result; it is written to effective_config.ini in any case");
  const auto& start = cli.number("", "start",
                                 "initialize with the records from T on: seconds after the first "
                                 "record, or a UNIX stamp if T > 1e8",
                                 0, range::atLeast(0), "T", "the first record");
  const auto& every =
      cli.number("", "every",
                 "initialize every S seconds along the recording (from --start), "
                 "each start in its own folder, with starts.csv/.md/.png; at "
                 "most " +
                     std::to_string(kMaxStarts) + " starts a run, and S at least the window / " +
                     std::to_string(kMaxOpenStarts) + " (at most " +
                     std::to_string(kMaxOpenStarts) + " initializations open at once)",
                 0, range::above(0), "S", "off");
  const auto& starts = cli.text("", "starts",
                                "initialize at each start in FILE (one per line, as --start), "
                                "as --every does",
                                "", "FILE", "none");
  const auto& check_all = cli.flag("", "check-all",
                                   "read and check the whole file (by default reading stops once "
                                   "the state is ready)");
  const auto& salvage = cli.flag("", "salvage",
                                 "read a rawlog cut short (e.g. a recording when the power went "
                                 "off) up to its last whole record, with a warning naming where "
                                 "it stopped");
  const auto& no_index =
      cli.flag("", "no-index", "neither use nor write the seek index <input>.freeinit.idx");
  if (const auto code = cli.parse(argc, argv)) return *code;
  FreeInitApp app;
  app.params.config_file = ini.value;
  app.params.rawlog = rawlog.value;
  if (const auto problem = app.params.argumentsProblem(); !problem.empty())
    return cli.usageError(problem);
  return app_support::runMain(cli.program(), [&] {
    app.params.out_dir = out.given ? out.value : ini.given ? kDefaultOutDir : "";
    app.params.progress = !quiet.value;
    app.params.echo_config = print_config.value;
    app.params.progress_terminal = isatty(STDOUT_FILENO) != 0;
    if (start.given) app.params.start = start.value;
    app.params.every = every.value;
    app.params.starts_file = starts.value;
    app.params.check_all = check_all.value;
    app.params.salvage = salvage.value;
    app.params.index.use = !no_index.value;
    app.params.command = "freeinit";
    for (int i = 1; i < argc; ++i) app.params.command += std::string(" ") + argv[i];
    return app.run(std::cout);
  });
}

}  // namespace freeinit::apps
