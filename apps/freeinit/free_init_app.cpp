#include "free_init_app.h"

#include <freeinit/app_support/command_line.h>
#include <freeinit/app_support/file_kind.h>
#include <freeinit/app_support/ingest.h>
#include <freeinit/app_support/ingest_sources.h>
#include <freeinit/app_support/output_set.h>
#include <freeinit/app_support/output_writers.h>
#include <freeinit/app_support/progress_bar.h>
#include <freeinit/app_support/result_files.h>
#include <freeinit/app_support/snapshots.h>
#include <freeinit/app_support/stop_signal.h>
#include <freeinit/input_checks.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <ctime>
#include <deque>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <memory>
#include <ostream>
#include <sstream>

namespace freeinit::apps {
namespace {

namespace fs = std::filesystem;

std::string v3(const Vec3& v) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(4) << v.x() << " " << v.y() << " " << v.z();
  return os.str();
}

constexpr const char* kStateFile = "initial_state.ini";
constexpr const char* kErrorsFile = "errors_wrt_gt.ini";
constexpr const char* kConfigFile = "effective_config.ini";

/// The starts of a run, in increasing order: one (possibly -inf: from the first record), a
/// list, or `first + k * every` without end.
class StartPlan {
 public:
  static StartPlan single(double t) { return StartPlan({t}, 0); }
  static StartPlan list(std::vector<double> t) { return StartPlan(std::move(t), 0); }
  static StartPlan every(double t0, double step) { return StartPlan({t0}, step); }

  std::optional<double> peek() const {
    if (step_ > 0) return list_.front() + static_cast<double>(next_) * step_;
    if (next_ < list_.size()) return list_[next_];
    return std::nullopt;
  }
  std::size_t index() const { return next_; }
  void pop() { ++next_; }
  /// The explicit starts not reached (none for `every`).
  std::vector<double> rest() const {
    if (step_ > 0) return {};
    return {list_.begin() + static_cast<std::ptrdiff_t>(next_), list_.end()};
  }

 private:
  StartPlan(std::vector<double> t, double step) : list_(std::move(t)), step_(step) {}
  std::vector<double> list_;
  double step_;
  std::size_t next_ = 0;
};

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
      app_support::verdictOf(result, config.core.velocimeter.doppler_sigma);
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
  if (!config_file.empty()) return "";  // the configuration's and the rawlog's readers check
  const app_support::FileKind input = app_support::fileKind(rawlog);
  if (input == app_support::FileKind::Ini)
    return "missing <input.rawlog>: '" + rawlog + "' is " + app_support::describe(input) +
           " (freeinit [<config.ini>] <input.rawlog>)";
  if (input == app_support::FileKind::Text || input == app_support::FileKind::RosBag ||
      input == app_support::FileKind::Binary)
    return "<input.rawlog> '" + rawlog + "': not an MRPT rawlog (it is " +
           app_support::describe(input) + ")";
  return "";
}

double startTime(double value, double first) {
  return value > kUnixStampThreshold ? value : first + value;
}

std::vector<double> readStartsFile(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw mrpt_plugins::InputError(path + ": cannot open the starts file");
  std::vector<double> out;
  std::string line;
  for (int n = 1; std::getline(f, line); ++n) {
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.erase(hash);
    std::istringstream is(line);
    double v = 0;
    if (!(is >> v)) {
      if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
      throw mrpt_plugins::InputError(path + ": line " + std::to_string(n) + ": '" + line +
                                     "' is not a number");
    }
    std::string rest;
    if (is >> rest)
      throw mrpt_plugins::InputError(path + ": line " + std::to_string(n) + ": one start per line");
    if (!std::isfinite(v) || v < 0)
      throw mrpt_plugins::InputError(path + ": line " + std::to_string(n) +
                                     ": a start must be >= 0");
    if (!out.empty() && !(v > out.back()))
      throw mrpt_plugins::InputError(path + ": line " + std::to_string(n) +
                                     ": starts must increase (after " +
                                     input::formatStamp(out.back()) + ")");
    out.push_back(v);
  }
  if (out.empty()) throw mrpt_plugins::InputError(path + ": no start in the file");
  return out;
}

int FreeInitApp::run(std::ostream& log) {
  using Clock = std::chrono::steady_clock;
  const auto t_start = Clock::now();
  const bool multi = params.every > 0 || !params.starts_file.empty();
  if (params.every < 0 || !std::isfinite(params.every))
    throw std::invalid_argument("--every must be > 0");
  if (params.every > 0 && !params.starts_file.empty())
    throw std::invalid_argument("--every and --starts exclude each other");
  if (params.start && !(*params.start >= 0)) throw std::invalid_argument("--start must be >= 0");
  if (const std::string problem = params.argumentsProblem(); !problem.empty())
    throw std::invalid_argument(problem);
  rows.clear();
  warnings.clear();
  result = InitResult{};
  errors_wrt_gt.reset();
  // A new folder for this run when none is given; removed again if the run fails.
  EmptyFolderSweep sweep;
  out_dir = params.out_dir;
  if (out_dir.empty()) {
    if (!fs::exists(params.new_out_root)) sweep.add(params.new_out_root);
    out_dir = createNewOutputFolder(params.new_out_root, params.rawlog);
    sweep.add(out_dir);
  }
  // The outputs' set: locked now, installed as a whole at the end; on any failure (an exception
  // through here) the staging folder goes and the earlier run's outputs stay as they were.
  app_support::OutputSet set(out_dir, "", app_support::folderSetOptions(), log);

  // 1. Configuration (the defaults without a file), echoed.
  config = params.config_file.empty() ? app_support::loadAppConfigFromText("", "the defaults")
                                      : app_support::loadAppConfig(params.config_file);
  std::ostringstream effective;
  app_support::dumpAppConfig(config, effective);
  if (params.echo_config)
    log << "Effective configuration ("
        << (params.config_file.empty() ? "the defaults: no configuration file" : params.config_file)
        << "):\n"
        << effective.str() << "\n";

  // 2. The starts.
  log << "Reading " << params.rawlog << "\n";
  mrpt_plugins::RawlogReader reader(params.rawlog, params.index);
  reader.setSalvage(params.salvage);
  reader.setMaxRecordBytes(static_cast<std::size_t>(config.input.max_record_mb * 1e6));
  index_used = reader.indexLoaded();
  if (index_used) log << "  seek index found (" << reader.index().records.size() << " records)\n";
  std::optional<double> first;
  if (params.start || multi) {
    first = reader.firstTime();
    if (!first) throw mrpt_plugins::InputError(params.rawlog + ": no record has a timestamp");
  }
  const double from =
      params.start ? startTime(*params.start, *first) : -std::numeric_limits<double>::infinity();
  StartPlan plan = StartPlan::single(from);
  if (params.every > 0) {
    plan = StartPlan::every(params.start ? from : *first, params.every);
  } else if (!params.starts_file.empty()) {
    std::vector<double> t = readStartsFile(params.starts_file);
    for (double& x : t) x = startTime(x, *first);
    plan = StartPlan::list(std::move(t));
  }
  if (params.start)
    log << "  start at " << input::formatStamp(from) << " (" << from - *first
        << " s after the first record)\n";

  std::vector<app_support::TruthSample> truth;
  const std::string truth_file = app_support::truthPathFor(params.rawlog);
  if (fs::is_regular_file(truth_file)) truth = app_support::readTruthCsv(truth_file);

  // 3. One pass: records -> items -> checks -> the sessions whose start has come.
  app_support::ObservationDecoder decoder(config.input);
  app_support::RecordChecker checker(config);
  std::deque<Slot> active;
  std::vector<std::string> outside;  // bad records no session took
  std::optional<std::string> read_error;
  std::vector<app_support::IngestItem> items;
  std::vector<app_support::CheckedItem> checked;
  app_support::ProgressBar bar(log, "  reading", "MB", params.progress_terminal, 1e6);
  const fs::path out(out_dir);
  int exit_code = 0;

  auto dispatch = [&](const app_support::CheckedItem& c) {
    bool taken = false;
    for (auto& s : active) {
      if (s.session->done() || !(c.item.t >= s.start)) continue;
      s.session->push(c);
      taken = true;
    }
    if (!taken && !c.ok())
      outside.push_back(params.rawlog + ": record " + std::to_string(c.item.record) + ": " +
                        c.problem + " (not used: outside every initialization window)");
  };

  // One start's end: its log lines, outputs and table row. `at_end`: the file ended before its
  // window closed (listed, but not a failure to initialize).
  auto finalize = [&](Slot& slot, bool at_end) {
    app_support::InitSession& s = *slot.session;
    for (const auto& w : s.warnings()) {
      log << "Warning: " << w << "\n";
      warnings.push_back(w);
    }
    if (!multi) {
      if (s.failed()) {
        for (const auto& e : s.errors()) log << "Error: " << e << "\n";
        const auto n = s.errors().size();
        throw mrpt_plugins::InputError(
            s.errors().front() +
            (n > 1 ? " (and " + std::to_string(n - 1) + " more, listed above)" : ""));
      }
      // The file ended before the window closed.
      if (!s.ready() || s.result().state.status == InitStatus::NotEnoughData)
        throw mrpt_plugins::InputError(s.endOfDataReason());
      result = s.result();
      log << "Input: " << s.imuCount() << " IMU samples and " << s.frameCount()
          << " point clouds from " << input::formatStamp(s.firstTime().value_or(0)) << " to "
          << input::formatStamp(s.lastTime().value_or(0)) << "\n";
      return;
    }
    StartRow row;
    row.index = slot.index;
    row.start = slot.start;
    row.start_offset = slot.start - *first;
    const std::string name = startFolderName(row.start_offset);
    if (s.failed()) {
      row.status = "input_error";
      for (const auto& e : s.errors()) row.message += (row.message.empty() ? "" : "; ") + e;
    } else if (!s.ready() || (at_end && s.result().state.status == InitStatus::NotEnoughData)) {
      // The file ends before the window closes: listed, no outputs.
      row.status = toString(InitStatus::NotEnoughData);
      std::ostringstream why;
      why << std::setprecision(3) << "the recording ends "
          << s.lastTime().value_or(slot.start) - slot.start
          << " s after this start, before a window closes";
      row.message = why.str();
    } else {
      const InitResult& r = s.result();
      row.state = r.state;
      row.status = toString(r.state.status);
      row.message = r.state.message;
      std::optional<app_support::TruthErrors> errs;
      if (r.state.ok()) {
        row.window_begin = r.trajectory.front().t;
        if (!truth.empty() && app_support::truthAt(truth, r.state.timestamp)) {
          row.truth = stateNees(r.state, truth);
          errs = row.truth->errors;
        }
      }
      writeStateSet(set, name + "/", config, r, errs, truth, nullptr);
      row.folder = name;
    }
    log << "Start " << row.index << " at " << std::fixed << std::setprecision(3) << row.start_offset
        << " s: " << row.status << std::defaultfloat
        << (row.message.empty() ? "" : " (" + row.message + ")");
    if (row.state && row.state->ok())
      log << ", |v_b| " << std::setprecision(4) << row.state->v_b().norm() << " m/s"
          << std::defaultfloat;
    if (row.truth)
      log << ", errors: velocity " << row.truth->errors.velocity << " m/s, gravity "
          << row.truth->errors.gravity_deg << " deg";
    log << (row.folder.empty() ? "" : " -> " + (out / row.folder).string()) << "\n";
    const bool cut_by_end = at_end && row.status == toString(InitStatus::NotEnoughData);
    if (row.status != toString(InitStatus::Ok) && !cut_by_end) exit_code = 3;
    rows.push_back(std::move(row));
  };

  auto finalizeDone = [&] {
    for (auto it = active.begin(); it != active.end();) {
      if (!it->session->done()) {
        ++it;
        continue;
      }
      finalize(*it, false);
      it = active.erase(it);
    }
  };

  bool stopped_early = false;
  for (;;) {
    if (active.empty() && !params.check_all) {
      const auto next = plan.peek();
      if (!next) {
        stopped_early = !reader.atEnd();
        break;
      }
    }
    app_support::throwIfStopRequested();
    mrpt_plugins::RawlogObject rec;
    try {
      // Idle: straight to the next start (no record at or after it: the end).
      if (active.empty() && !params.check_all && !reader.seekToTime(*plan.peek())) break;
      if (!reader.next(rec)) break;
    } catch (const mrpt_plugins::InputError& e) {
      read_error = e.what();
      break;
    }
    if (params.progress) bar.update(reader.bytesRead(), reader.fileBytes());
    items.clear();
    decoder.decode(rec.index, rec.object, items);
    rec.object.reset();
    for (auto& item : items) {
      while (std::isfinite(item.t)) {
        const auto next = plan.peek();
        if (!next || item.t < *next) break;
        active.push_back({plan.index(), *next,
                          std::make_unique<app_support::InitSession>(config, params.rawlog)});
        plan.pop();
      }
      if (active.empty() && !params.check_all) continue;  // before the next start: not needed
      checked.clear();
      checker.push(std::move(item), checked);
      for (const auto& c : checked) dispatch(c);
    }
    finalizeDone();
  }
  const std::size_t last_record = reader.nextRecord();
  records_read = reader.recordsDeserialized();
  read_to_end = reader.atEnd();
  salvage_stop = reader.salvageStop();
  if (!salvage_stop.empty()) {
    log << "Warning: " << salvage_stop << "\n";
    warnings.push_back(salvage_stop);
  }

  if (read_error) {
    // Unreadable from here on: the open windows fail; what comes after is not checked.
    for (auto& s : active) s.session->fail(*read_error);
    if (!multi && active.empty() && plan.peek())
      throw mrpt_plugins::InputError(*read_error);  // not reached
    if (active.empty() && !plan.peek())
      outside.push_back(*read_error + "; the rest of the file was not checked");
  } else if (!stopped_early) {
    // The end of the file: windows still open close with what is there.
    checked.clear();
    checker.finish(checked);
    for (const auto& c : checked) dispatch(c);
    for (auto& s : active) s.session->finish();
  }
  for (auto& s : active) finalize(s, !read_error);
  active.clear();
  if (!multi && plan.peek())
    throw mrpt_plugins::InputError(
        params.rawlog + ": no record at or after the start " + input::formatStamp(*plan.peek()) +
        (first ? " (" + std::to_string(*plan.peek() - *first) + " s after the first record)"
               : std::string()));
  if (multi) {
    // Starts the file does not reach.
    std::size_t k = plan.index();
    for (double t : plan.rest()) {
      StartRow row;
      row.index = k++;
      row.start = t;
      row.start_offset = t - *first;
      row.status = read_error ? "unreadable" : toString(InitStatus::NotEnoughData);
      row.message = read_error ? *read_error : "no record at or after this start";
      rows.push_back(row);
      if (read_error) exit_code = 3;
    }
    if (read_error && params.every > 0)
      log << "Warning: no start from " << std::fixed << std::setprecision(3)
          << *plan.peek() - *first << std::defaultfloat << " s on: " << *read_error << "\n";
  }
  if (params.progress)
    bar.finish(stopped_early ? "(state ready: the rest of the input is not needed)" : "");
  for (const auto& w : outside) {
    log << "Warning: " << w << "\n";
    warnings.push_back(w);
  }
  if (stopped_early)
    log << "Read up to record " << (last_record == 0 ? 0 : last_record - 1)
        << "; the rest was not checked (use --check-all)\n";
  std::string why;
  index_written = reader.saveIndex(&why);
  if (!index_written.empty()) log << "Seek index written to " << index_written << "\n";
  if (!why.empty()) log << "Warning: the seek index could not be written: " << why << "\n";

  if (multi) {
    set.write(kConfigFile, [&](const std::string& p) {
      writeFileAtomically(p, [&](std::ostream& o) { o << effective.str(); });
    });
    std::sort(rows.begin(), rows.end(),
              [](const StartRow& a, const StartRow& b) { return a.index < b.index; });
    if (std::any_of(rows.begin(), rows.end(),
                    [](const StartRow& r) { return r.state && r.state->ok(); }))
      set.write("starts.png", [&](const std::string& p) {
        renderStartPlot(p, rows, config.output.snapshot_width, config.output.snapshot_height);
      });
    set.write("starts.csv", [&](const std::string& p) { writeStartTableCsv(p, rows); });
    set.write("starts.md", [&](const std::string& p) {
      writeStartTableMarkdown(p, rows, params.rawlog,
                              params.command.empty() ? "freeinit" : params.command);
    });
    set.commit();
    const double secs = std::chrono::duration<double>(Clock::now() - t_start).count();
    std::size_t ok = 0;
    for (const auto& r : rows) ok += r.status == toString(InitStatus::Ok) ? 1 : 0;
    log << rows.size() << " start(s), " << ok << " initialized; table in "
        << (out / "starts.md").string() << " (" << std::setprecision(3) << secs << " s total)\n";
    return rows.empty() ? 3 : exit_code;
  }

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
    app_support::printVerdict(
        log, app_support::verdictOf(result, config.core.velocimeter.doppler_sigma));
  for (const auto& w : s.warnings) log << "  warning: " << w << "\n";
  if (config.extrinsics.from_sensor_pose && checker.declaredExtrinsics())
    log << "Extrinsics from sensorPose: p_bl = " << v3(checker.declaredExtrinsics()->p_bl)
        << " m\n";

  // 4. Ground truth, when it sits beside the rawlog.
  if (!truth.empty() && s.ok()) {
    errors_wrt_gt = app_support::compareWithTruth(s, truth);
    log << "Errors w.r.t. ground truth (" << truth_file << "):\n"
        << "  velocity    " << errors_wrt_gt->velocity << " m/s\n"
        << "  gravity     " << errors_wrt_gt->gravity_deg << " deg\n"
        << "  gyro bias   " << errors_wrt_gt->gyro_bias << " rad/s\n"
        << "  accel bias  " << errors_wrt_gt->accel_bias << " m/s^2\n";
  }

  // 5. The outputs, staged, then installed as one set.
  const std::string effective_text = effective.str();
  writeStateSet(set, "", config, result, errors_wrt_gt, truth, &effective_text);
  set.commit();
  const double secs = std::chrono::duration<double>(Clock::now() - t_start).count();
  log << "Outputs in " << out.string() << " (" << std::setprecision(3) << secs << " s total)\n";
  return s.ok() ? 0 : 3;
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
  const auto& rawlog = cli.positional("input.rawlog", "input rawlog");
  const auto& out =
      cli.text("o", "out", "output folder (its earlier outputs are replaced)", "", "DIR",
               std::string(kDefaultOutDir) +
                   "; without <config.ini> a new folder for each run, "
                   "freeinit_out/<input>.<time>");
  const auto& quiet = cli.flag("q", "quiet",
                               "no progress bar and no listing of the effective configuration "
                               "(still written to effective_config.ini)");
  const auto& start = cli.number("", "start",
                                 "initialize with the records from T on: seconds after the first "
                                 "record, or a UNIX stamp if T > 1e8",
                                 0, range::atLeast(0), "T", "the first record");
  const auto& every = cli.number("", "every",
                                 "initialize every S seconds along the recording (from --start), "
                                 "each start in its own folder, with starts.csv/.md/.png",
                                 0, range::atLeast(0), "S", "off");
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
    app.params.echo_config = !quiet.value;
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
