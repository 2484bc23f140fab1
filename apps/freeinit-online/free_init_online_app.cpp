#include "free_init_online_app.h"

#include <freeinit/app_support/command_line.h>
#include <freeinit/app_support/ingest.h>
#include <freeinit/app_support/ingest_sources.h>
#include <freeinit/app_support/output_set.h>
#include <freeinit/app_support/output_writers.h>
#include <freeinit/app_support/result_files.h>
#include <freeinit/app_support/stop_signal.h>
#include <freeinit/mrpt_plugins/conversions.h>
#include <freeinit/mrpt_plugins/rawlog_reader.h>
#include <freeinit/mrpt_plugins/rawlog_writer.h>
#include <freeinit/mrpt_plugins/register.h>
#include <freeinit/mrpt_plugins/stream_conversions.h>

#include <array>
#include <chrono>
#include <condition_variable>
#include <csignal>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>
#include <mutex>
#include <optional>
#include <ostream>
#include <sstream>
#include <thread>

namespace freeinit::apps {
namespace {

constexpr const char* kStateFile = "initial_state.ini";
constexpr const char* kStatsFile = "stream_stats.ini";
constexpr const char* kConfigFile = "effective_config.ini";

using Clock = std::chrono::steady_clock;
double secondsBetween(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

// What the recorder writes: an item as it was received (its exact stamp, a frame's points shared
// with the estimator, never changed) and how to label it.
struct Recorded {
  app_support::IngestItem item;
  std::string label;
  Extrinsics extrinsics;  ///< a frame's, as the stream declared it
};

// Converts the received items to MRPT observations and serializes and compresses them (a
// RawlogWriter) in its own thread, off the estimator's path. The queue is bounded: when the disk
// cannot keep up, push() waits, and the source's bounded queue then drops (and counts) instead.
// A write that fails (a full disk) stops the recording: the file keeps every whole record up to
// there and is closed properly (RawlogWriter::keepPartial()), and so is one destroyed without
// close() (an error on the way).
class RecordWriter {
 public:
  RecordWriter(const std::string& path, std::size_t max_queued)
      : writer_(path), max_queued_(max_queued) {
    writer_.keepPartial();  // a recording is never lost, even when writing or closing it fails
    thread_ = std::thread([this] { loop(); });
  }
  ~RecordWriter() { stop(); }

  /// Queues `r`; false when the recording has stopped (a write failed).
  bool push(Recorded r) {
    std::unique_lock<std::mutex> lock(mutex_);
    room_.wait(lock, [&] { return queue_.size() < max_queued_ || !error_.empty(); });
    if (!error_.empty()) return false;
    queue_.push_back(std::move(r));
    ready_.notify_one();
    return true;
  }
  /// Writes what is queued (unless writing failed), closes the file and renames it onto its
  /// path. Returns why the recording stopped early, the system's reason ("" if it did not).
  std::string close() {
    stop();
    try {
      writer_.commit();
    } catch (const std::exception& e) {
      if (error_.empty()) error_ = writer_.error().empty() ? e.what() : writer_.error();
    }
    return error_;
  }
  /// Whole records in the file, and the stamps of the first and the last of them [ns].
  std::size_t records() const { return writer_.records(); }
  std::int64_t firstStampNs() const { return first_ns_; }
  std::int64_t lastStampNs() const { return last_ns_; }

 private:
  void stop() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      closing_ = true;
    }
    ready_.notify_one();
    if (thread_.joinable()) thread_.join();
  }
  /// The observation freeinit-sim would have written: stamps on MRPT's clock from the exact
  /// nanoseconds, the cloud's sensorPose from the declared extrinsics (IMU at the origin).
  static mrpt::obs::CObservation::Ptr toObservation(const Recorded& r) {
    const app_support::IngestItem& it = r.item;
    if (it.kind == app_support::IngestItem::Kind::Imu) {
      auto obs = mrpt_plugins::imuToObservation(it.imu, r.label);
      obs->timestamp = mrpt_plugins::fromUnixNs(*it.stamp_ns);
      return obs;
    }
    auto obs = mrpt_plugins::frameToObservation(0.0, it.frame->points, r.extrinsics, r.label);
    obs->timestamp = mrpt_plugins::fromUnixNs(*it.stamp_ns);
    return obs;
  }
  void loop() {
    for (;;) {
      Recorded r;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        ready_.wait(lock, [&] { return !queue_.empty() || closing_; });
        if (queue_.empty()) return;
        r = std::move(queue_.front());
        queue_.pop_front();
      }
      room_.notify_one();
      try {
        writer_.write(*toObservation(r));
        if (writer_.records() == 1) first_ns_ = *r.item.stamp_ns;
        last_ns_ = *r.item.stamp_ns;
      } catch (const std::exception& e) {
        std::lock_guard<std::mutex> lock(mutex_);
        error_ = writer_.error().empty() ? e.what() : writer_.error();
        queue_.clear();  // not written: the recording ends at its last whole record
        room_.notify_all();
        return;
      }
    }
  }

  mrpt_plugins::RawlogWriter writer_;
  std::size_t max_queued_;
  std::mutex mutex_;
  std::condition_variable ready_, room_;
  std::deque<Recorded> queue_;
  bool closing_ = false;
  std::string error_;
  std::int64_t first_ns_ = 0, last_ns_ = 0;
  std::thread thread_;
};

const char* const kSourceName = "live stream";

/// Room held on the disk for ending the run when the recording fills it: the recording's end,
/// stream_stats.ini and the install journal, a few file-system blocks each [bytes].
constexpr std::size_t kFullDiskReserve = 64 * 1024;

/// The output set's options: the recording (a file name in the output folder) and its
/// statistics are kept, never deleted.
app_support::OutputSetOptions onlineSetOptions(const FreeInitOnlineAppParams& p) {
  if (p.record.find('/') != std::string::npos)
    throw std::invalid_argument("--record " + p.record +
                                ": a file name in the output folder, without '/'");
  app_support::OutputSetOptions options = app_support::folderSetOptions();
  if (!p.record.empty()) {
    options.recording = p.record;
    options.reserve_bytes = kFullDiskReserve;
  }
  options.recording_companion = kStatsFile;
  return options;
}

/// "no space left on the device (out/x is full)", or the system's reason as it is.
std::string reasonText(const app_support::OutputSet& set, const std::string& why) {
  return set.noSpace(why) ? "no space left on the device (" + set.dir() + " is full)" : why;
}

/// One run of freeinit-online, step by step (FreeInitOnlineApp::run() calls them in order); what
/// it finds goes to the app's members.
///
/// The outputs are one set (output_set.h): the state (with effective_config.ini) is installed the
/// moment the window closes, replacing the earlier run's outputs (its recording renamed, never
/// deleted); the rest when the stream ends. A run that ends before the window closed leaves the
/// earlier outputs as they were (its recording kept beside them).
class OnlineRun {
 public:
  OnlineRun(FreeInitOnlineApp& app, std::ostream& log)
      : app_(app),
        p_(app.params),
        log_(log),
        t_start_(Clock::now()),
        set_(p_.out_dir, "", onlineSetOptions(p_), log) {}

  /// The configuration (echoed, and staged as effective_config.ini) and the recording, written
  /// into the staging folder and kept whatever happens.
  void prepare() {
    std::vector<std::string> notices;  // keys given under their former names
    app_.config = app_support::loadAppConfig(p_.config_file, &notices);
    for (const std::string& n : notices) log_ << n << "\n";
    std::ostringstream effective;
    app_support::dumpAppConfig(app_.config, effective);
    log_ << "Effective configuration (" << p_.config_file << "):\n" << effective.str() << "\n";
    const app_support::InputParams& in = app_.config.input;
    labels_ = {in.imu_label.empty() ? "IMU" : in.imu_label,
               in.lidar_label.empty() ? "LIDAR" : in.lidar_label};
    state_file_ = set_.finalPath(kStateFile);
    app_.record_path = p_.record.empty() ? "" : set_.finalPath(p_.record);
    set_.write(kConfigFile, [&](const std::string& path) {
      writeFileAtomically(path, [&](std::ostream& o) { o << effective.str(); });
    });
    if (!app_.record_path.empty()) rec_ = std::make_unique<RecordWriter>(set_.path(p_.record), 128);
  }

  /// The source (the app's, or the UDP receiver) and the ingest path behind it, as offline: wire
  /// items -> record checks -> one session.
  void startSource() {
    src_ = app_.source ? std::move(app_.source) : std::make_unique<net::UdpStreamSource>(p_.source);
    src_->start();
    if (const auto* udp = dynamic_cast<const net::UdpStreamSource*>(src_.get())) {
      log_ << "Listening on UDP " << p_.source.address << ":" << udp->port() << " (receive buffer "
           << udp->receiveBufferGranted() << " bytes)\n";
      log_.flush();  // a live tool's log is followed as it runs (e.g. tail -f on a file)
      if (app_.on_listening) app_.on_listening(udp->port());
    }
    checker_.emplace(app_.config);
    session_.emplace(app_.config, kSourceName, false);
    accel_scale_ = app_.config.input.imu_accel_in_g ? kGravity : 1.0;
    app_.ready_live = false;
    app_.stats_at_ready = {};
    app_.recorded = 0;
  }

  /// Until the stream ends (end-of-stream marker, idle or time limits, a stop signal, or an
  /// input error), feeding every item to the recording and, until it is done, to the session.
  void receive() {
    auto last_data = Clock::now();
    std::vector<net::StreamEvent> events;
    while (!end_) {
      if (const int sig = app_support::stopSignal()) {
        // The normal way to stop a live tool: the end of the stream, with every output written.
        log_ << "Stopped by " << app_support::signalName(sig) << ": end of the stream\n";
        app_support::clearStopRequest();
        stopped_by_signal_ = sig;
        break;
      }
      events.clear();
      src_->poll(events, 0.05);
      const auto now = Clock::now();
      if (!events.empty()) {
        last_data = now;
        data_seen_ = true;
      } else if (data_seen_ && p_.idle_timeout > 0 &&
                 secondsBetween(last_data, now) > p_.idle_timeout) {
        log_ << "No data for " << p_.idle_timeout << " s: end of the stream\n";
        break;
      } else if (!data_seen_ && p_.wait_first > 0 &&
                 secondsBetween(t_start_, now) > p_.wait_first) {
        log_ << "No data within " << p_.wait_first << " s\n";
        break;
      }
      if (p_.max_duration > 0 && secondsBetween(t_start_, now) > p_.max_duration) {
        log_ << "Maximum duration reached\n";
        break;
      }
      for (auto& e : events) {
        handle(e);
        if (end_) break;
      }
      if (!input_error_.empty()) break;
    }
    src_->stop();
    app_.stats = src_->stats();
  }

  /// Closes the recording (removed when nothing was recorded; kept up to its last whole record
  /// when writing it failed); then, without any data, the run fails with nothing written.
  void closeRecording() {
    if (rec_) {
      // The recording's end must fit even on a full disk: the reserve is given back for it, and
      // taken again, if there is room, for what follows.
      set_.releaseReserve();
      recording_error_ = rec_->close();
      set_.holdReserve();
      recording_.records = rec_->records();
      recording_.first_ns = rec_->firstStampNs();
      recording_.last_ns = rec_->lastStampNs();
      rec_.reset();
      if (recording_.records == 0) {
        std::filesystem::remove(set_.path(p_.record));  // nothing was recorded
      } else {
        log_ << "Recorded " << recording_.records << " observations to " << app_.record_path
             << "\n";
      }
    }
    if (!data_seen_) {
      std::ostringstream within;  // a signal before --wait ran out: "before SIGINT" only
      if (p_.wait_first > 0 && stopped_by_signal_ == 0)
        within << " within " << p_.wait_first << " s";
      throw mrpt_plugins::InputError(
          std::string(kSourceName) + ": no data received" + within.str() +
          (stopped_by_signal_ != 0 ? " before " + app_support::signalName(stopped_by_signal_)
                                   : "") +
          "; " + set_.leftBehind());
    }
  }

  /// stream_stats.ini (kept with the recording), with the latency when the state was written
  /// live. An input error then ends the run: the recording and its statistics are kept
  /// (abandon() installs them), the rest goes.
  void writeStreamStats() {
    const net::SourceStats& stats = app_.stats;
    const net::SourceStats& at_ready = app_.stats_at_ready;
    const OnlineLatency& latency = app_.latency;
    std::ostringstream st;
    net::printStats(st, stats);
    log_ << "Stream statistics:\n" << st.str();
    set_.write(kStatsFile, [&](const std::string& path) {
      writeFileAtomically(path, [&](std::ostream& o) {
        o << "[stream]\n"
          << st.str()
          << "recorded            = " << (p_.record.empty() ? app_.recorded : recording_.records)
          << "\n";
        if (!recording_error_.empty())
          o << std::fixed << std::setprecision(3)
            << "; the recording stopped early: it holds every whole record up to the failure\n"
            << "recording_stopped   = " << reasonText(set_, recording_error_) << "\n"
            << "recording_stopped_after_s = "
            << 1e-9 * static_cast<double>(recording_.last_ns - recording_.first_ns)
            << "  ; of the stream, at its last whole record\n"
            << std::setprecision(6) << "recording_last_stamp = " << 1e-9 * recording_.last_ns
            << "  ; UNIX s\n"
            << std::defaultfloat;
        if (stopped_by_signal_ != 0)
          o << "stopped_by          = " << app_support::signalName(stopped_by_signal_) << "\n";
        if (app_.ready_live)
          o << std::setprecision(6) << "latency_total_ms    = " << 1e3 * latency.total
            << "\nlatency_queue_ms    = " << 1e3 * latency.queue
            << "\nlatency_estimator_ms= " << 1e3 * latency.estimator
            << "\nlatency_write_ms    = " << 1e3 * latency.write
            << "\n; stream anomalies before the state was written (data possibly in the window)"
            << "\nanomalies_before_ready = " << at_ready.anomalies()
            << "\nlost_before_ready   = " << at_ready.receiver.lost
            << "\nqueue_dropped_imu_before_ready    = " << at_ready.queue_dropped_imu
            << "\nqueue_dropped_frames_before_ready = " << at_ready.queue_dropped_frames << "\n";
      });
    });
    if (stats.anomalies() > 0)
      log_ << "Warning: " << stats.anomalies()
           << " datagrams or items lost, dropped or rejected (see stream_stats.ini)\n";
    if (!input_error_.empty()) throw mrpt_plugins::InputError(input_error_);
    if (!recording_error_.empty()) {
      // The other outputs are not written (the disk is full, or the recording's own error); the
      // state, if the window closed, stays with the recording and its statistics.
      std::ostringstream m;
      m << app_.record_path << ": the recording stopped after " << recording_.records
        << " whole records (" << std::fixed << std::setprecision(3)
        << 1e-9 * static_cast<double>(recording_.last_ns - recording_.first_ns)
        << " s of the stream" << (app_.ready_live ? "" : ", before the window closed")
        << "): " << reasonText(set_, recording_error_) << "; " << set_.leftBehind();
      throw app_support::OutputError(m.str());
    }
  }

  /// A session the stream ended before: given the end of the data, it initializes or says why
  /// not (an InputError).
  void finishSession() {
    app_support::InitSession& session = *session_;
    if (!session.done()) {
      std::vector<app_support::CheckedItem> checked;
      checker_->finish(checked);
      for (const auto& c : checked) session.push(c);
      session.finish();
      if (session.failed()) {
        for (const auto& err : session.errors()) log_ << "Error: " << err << "\n";
        throw mrpt_plugins::InputError(session.errors().front());
      }
      if (!session.ready()) throw mrpt_plugins::InputError(session.endOfDataReason());
      writeState(session.result());
    }
    for (const auto& w : session.warnings()) log_ << "Warning: " << w << "\n";
    if (session.ready() && session.result().state.ok()) {
      app_support::printVerdict(log_, app_support::verdictOf(session.result(), dopplerSigma()));
      for (const auto& w : session.result().state.warnings) log_ << "  warning: " << w << "\n";
    }
    app_.result = session.result();
    if (stopped_by_signal_ != 0 && !app_.ready_live)
      log_ << "The stream was stopped by " << app_support::signalName(stopped_by_signal_)
           << " before the window closed\n";
  }

  /// The other outputs (as the offline app writes them), and the set installed.
  int writeOutputs() {
    const InitResult& result = app_.result;
    app_support::writeResultFiles(set_, "", app_.config.output, result, {});
    set_.commit();
    log_ << "Initialization: " << toString(result.state.status)
         << (result.state.message.empty() ? "" : " (" + result.state.message + ")") << "\n";
    return result.state.ok() ? 0 : 3;
  }

 private:
  double dopplerSigma() const { return app_.config.core.doppler.doppler_sigma; }

  void writeState(const InitResult& r) {
    set_.write(kStateFile, [&](const std::string& path) {
      const app_support::StateVerdict v = app_support::verdictOf(r, dopplerSigma());
      app_support::writeInitialStateIni(path, r.state, &v);
    });
  }

  /// One event of the stream: a sender's session start or end of stream, or an item for the
  /// recording and the session.
  void handle(net::StreamEvent& e) {
    using Kind = net::StreamEvent::Kind;
    if (e.kind == Kind::SessionStart) {
      log_ << "Sender session " << std::hex << e.session << std::dec
           << (++sessions_ > 1 ? " (the sender restarted)" : "") << "\n";
      return;
    }
    if (e.kind == Kind::EndOfStream) {
      log_ << "End of stream from the sender\n";
      if (p_.stop_at_end_of_stream) end_ = true;
      return;
    }
    const auto t_fed = Clock::now();
    const Extrinsics declared = e.frame.extrinsics;
    auto item = app_support::itemFromStream(std::move(e), app_.recorded, accel_scale_);
    if (!item) return;
    if (rec_ && !recording_stopped_) {
      const bool imu = item->kind == app_support::IngestItem::Kind::Imu;
      Recorded r;
      r.item.kind = item->kind;
      r.item.stamp_ns = item->stamp_ns;
      r.item.imu = item->imu;
      r.item.imu.accel = e.imu.accel;  // as received (the rawlog decoder applies the unit)
      r.item.frame = item->frame;
      r.label = imu ? labels_.imu : labels_.lidar;
      r.extrinsics = declared;
      if (!rec_->push(std::move(r))) {
        // Writing the recording failed (a full disk): the run ends here, with what it recorded.
        log_ << "The recording stopped (writing " << app_.record_path
             << " failed): end of the stream\n";
        recording_stopped_ = true;
        end_ = true;
        return;
      }
    }
    ++app_.recorded;
    app_support::InitSession& session = *session_;
    if (stopped_ || session.done()) return;
    checked_.clear();
    checker_->push(std::move(*item), checked_);
    for (const auto& c : checked_) session.push(c);
    if (session.done()) {
      done(e, t_fed);
      if (!input_error_.empty()) stopped_ = true;
    }
  }

  /// The moment the session is done while the stream runs: the state is written, or the input
  /// error stops the run.
  void done(const net::StreamEvent& e, Clock::time_point t_fed) {
    app_support::InitSession& session = *session_;
    if (session.failed()) {
      input_error_ = session.errors().front();
      for (const auto& err : session.errors()) log_ << "Error: " << err << "\n";
      return;
    }
    const auto t_processed = Clock::now();
    // The state goes out before the map is built (the map is for the outputs at the end); with
    // it, this run's set replaces the earlier one.
    writeState(session.resultBeforeMap());
    set_.install({kConfigFile, kStateFile});
    const auto t_written = Clock::now();
    OnlineLatency& latency = app_.latency;
    latency.queue = secondsBetween(e.received, t_fed);
    latency.estimator = secondsBetween(t_fed, t_processed);
    latency.write = secondsBetween(t_processed, t_written);
    latency.total = secondsBetween(e.received, t_written);
    app_.ready_live = true;
    const net::SourceStats& at_ready = app_.stats_at_ready = src_->stats();
    log_ << std::fixed << std::setprecision(3) << "State written to " << state_file_ << ": latency "
         << 1e3 * latency.total << " ms from the receipt of the last needed "
         << "measurement (queue and conversion " << 1e3 * latency.queue << ", estimator "
         << 1e3 * latency.estimator << ", write " << 1e3 * latency.write << ")\n"
         << std::defaultfloat;
    log_ << (at_ready.anomalies() > 0 ? "Warning: " : "")
         << "anomalies_before_ready = " << at_ready.anomalies() << " (" << at_ready.receiver.lost
         << " datagrams lost, " << at_ready.queue_dropped_imu << " IMU samples and "
         << at_ready.queue_dropped_frames << " frames dropped, "
         << at_ready.receiver.frames_incomplete + at_ready.receiver.frames_inconsistent
         << " frames incomplete or inconsistent)\n";
    log_.flush();
    if (p_.stop_when_ready) end_ = true;
  }

  FreeInitOnlineApp& app_;
  const FreeInitOnlineAppParams& p_;
  std::ostream& log_;
  Clock::time_point t_start_;
  app_support::OutputSet set_;
  mrpt_plugins::StreamLabels labels_;
  std::string state_file_;
  std::unique_ptr<RecordWriter> rec_;
  std::unique_ptr<net::StreamSource> src_;
  std::optional<app_support::RecordChecker> checker_;
  std::optional<app_support::InitSession> session_;
  double accel_scale_ = 1.0;
  std::vector<app_support::CheckedItem> checked_;
  std::string input_error_;
  std::string recording_error_;  ///< why the recording stopped early ("" if it did not)
  struct {
    std::size_t records = 0;                 ///< whole records in the recording
    std::int64_t first_ns = 0, last_ns = 0;  ///< their first and last stamps
  } recording_;
  bool recording_stopped_ = false;  ///< writing the recording failed: the stream ends
  bool data_seen_ = false;
  bool end_ = false;      ///< the stream ended (or the state is ready with stop_when_ready)
  bool stopped_ = false;  ///< an input error: nothing more is fed
  int stopped_by_signal_ = 0;
  int sessions_ = 0;  ///< sender sessions seen
};

// From the end of the stream on, a stop signal asks for what is already under way (the end of
// the stream, then the outputs, a few seconds): SIGINT, SIGTERM and SIGHUP are ignored until the
// run returns, and one that came since the stream ended is acknowledged, so that a late Ctrl-C
// does not cost the outputs (nor say that none was written while the state is there). SIGKILL
// still stops the process.
class StopSignalsIgnored {
 public:
  explicit StopSignalsIgnored(std::ostream& log) {
    struct sigaction ignore = {};
    ignore.sa_handler = SIG_IGN;
    sigemptyset(&ignore.sa_mask);
    for (std::size_t i = 0; i < kSignals.size(); ++i)
      sigaction(kSignals[i], &ignore, &previous_[i]);
    if (const int sig = app_support::stopSignal()) {
      log << app_support::signalName(sig) << " after the end of the stream: the outputs are "
          << "written first\n";
      app_support::clearStopRequest();
    }
  }
  ~StopSignalsIgnored() {
    for (std::size_t i = 0; i < kSignals.size(); ++i)
      sigaction(kSignals[i], &previous_[i], nullptr);
  }
  StopSignalsIgnored(const StopSignalsIgnored&) = delete;
  StopSignalsIgnored& operator=(const StopSignalsIgnored&) = delete;

 private:
  static constexpr std::array<int, 3> kSignals = {SIGINT, SIGTERM, SIGHUP};
  std::array<struct sigaction, 3> previous_{};
};

}  // namespace

int FreeInitOnlineApp::run(std::ostream& log) {
  mrpt_plugins::registerClasses();
  OnlineRun r(*this, log);
  r.prepare();
  r.startSource();
  r.receive();
  const StopSignalsIgnored finishing(log);
  r.closeRecording();
  r.writeStreamStats();
  r.finishSession();
  return r.writeOutputs();
}

int FreeInitOnlineApp::main(int argc, char** argv) {
  namespace range = freeinit::config;
  app_support::CommandLine cli(
      "freeinit-online",
      "initial state from a live Doppler LiDAR + IMU UDP stream, written as "
      "soon as the initialization window closes; the stream is recorded as a "
      "rawlog");
  const auto& ini = cli.positional("config.ini", "INI configuration file (ini/freeinit.ini)");
  const auto& out = cli.text("o", "out", "output folder", "freeinit_online_out", "DIR");
  const auto& record =
      cli.text("r", "record", "recording file name in the output folder (\"\": none)",
               "live.rawlog", "FILE");
  const auto& address =
      cli.text("a", "address", "local IPv4 address to listen on", "127.0.0.1", "IP");
  const auto& port = cli.integer("p", "port", "UDP port (0: any free port)", 47800, 0, 65535, "N");
  const auto& wait = cli.number("w", "wait", "give up if no data for S s at start (0: wait)", 0,
                                range::between(0, 86400), "S");
  const auto& idle = cli.number("i", "idle-timeout", "end after S s without data", 2.0,
                                range::aboveUpTo(0, 86400), "S");
  const auto& max_duration = cli.number("d", "max-duration", "end after S s (0: no limit)", 0,
                                        range::between(0, 1e7), "S");
  const auto& stop_ready = cli.flag("", "stop-when-ready", "end as soon as the state is written");
  const auto& ignore_end =
      cli.flag("", "ignore-end-marker", "keep listening after the sender's end-of-stream marker");
  if (const auto code = cli.parse(argc, argv)) return *code;
  return app_support::runMain(cli.program(), [&] {
    FreeInitOnlineApp app;
    app.params.config_file = ini.value;
    app.params.out_dir = out.value;
    app.params.record = record.value;
    app.params.source.address = address.value;
    app.params.source.port = static_cast<std::uint16_t>(port.value);
    app.params.wait_first = wait.value;
    app.params.idle_timeout = idle.value;
    app.params.max_duration = max_duration.value;
    app.params.stop_when_ready = stop_ready.value;
    app.params.stop_at_end_of_stream = !ignore_end.value;
    return app.run(std::cout);
  });
}

}  // namespace freeinit::apps
