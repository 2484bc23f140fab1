#include <freeinit/mrpt_plugins/conversions.h>
#include <freeinit/mrpt_plugins/free_init_online_app.h>
#include <freeinit/mrpt_plugins/ingest.h>
#include <freeinit/mrpt_plugins/ingest_sources.h>
#include <freeinit/mrpt_plugins/output_set.h>
#include <freeinit/mrpt_plugins/output_writers.h>
#include <freeinit/mrpt_plugins/rawlog_reader.h>
#include <freeinit/mrpt_plugins/rawlog_writer.h>
#include <freeinit/mrpt_plugins/register.h>
#include <freeinit/mrpt_plugins/result_files.h>
#include <freeinit/mrpt_plugins/stop_signal.h>
#include <freeinit/mrpt_plugins/stream_conversions.h>

#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <iomanip>
#include <memory>
#include <mutex>
#include <ostream>
#include <sstream>
#include <thread>

namespace freeinit::mrpt_plugins {
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
  IngestItem item;
  std::string label;
  Extrinsics extrinsics;  ///< a frame's, as the stream declared it
};

// Converts the received items to MRPT observations and serializes and compresses them (a
// RawlogWriter) in its own thread, off the estimator's path. The queue is bounded: when the disk
// cannot keep up, push() waits, and the source's bounded queue then drops (and counts) instead.
// Destroyed without commit() (an error on the way), it keeps what was written.
class RecordWriter {
 public:
  RecordWriter(const std::string& path, std::size_t max_queued)
      : writer_(path), max_queued_(max_queued) {
    writer_.keepPartial();  // a recording is never lost, even when closing it fails
    thread_ = std::thread([this] { loop(); });
  }
  ~RecordWriter() { stop(); }

  void push(Recorded r) {
    std::unique_lock<std::mutex> lock(mutex_);
    room_.wait(lock, [&] { return queue_.size() < max_queued_ || !error_.empty(); });
    if (!error_.empty()) throw std::runtime_error(error_);
    queue_.push_back(std::move(r));
    ready_.notify_one();
  }
  /// Writes what is queued, closes the file and renames it onto its path; throws if writing
  /// failed (then no file is left).
  void commit() {
    stop();
    if (!error_.empty()) throw std::runtime_error(error_);
    writer_.commit();
  }
  const std::string& path() const { return writer_.path(); }

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
    const IngestItem& it = r.item;
    if (it.kind == IngestItem::Kind::Imu) {
      auto obs = imuToObservation(it.imu, r.label);
      obs->timestamp = fromUnixNs(*it.stamp_ns);
      return obs;
    }
    auto obs = frameToObservation(0.0, it.frame->points, r.extrinsics, r.label);
    obs->timestamp = fromUnixNs(*it.stamp_ns);
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
      } catch (const std::exception& e) {
        std::lock_guard<std::mutex> lock(mutex_);
        error_ = std::string("recording: ") + e.what();
        room_.notify_all();
        return;
      }
    }
  }

  RawlogWriter writer_;
  std::size_t max_queued_;
  std::mutex mutex_;
  std::condition_variable ready_, room_;
  std::deque<Recorded> queue_;
  bool closing_ = false;
  std::string error_;
  std::thread thread_;
};

}  // namespace

int FreeInitOnlineApp::run(std::ostream& log) {
  registerClasses();
  const auto t_start = Clock::now();

  // The outputs are one set (output_set.h): the earlier run's go when this run's first data
  // arrive (its recording renamed, never deleted); the state is installed the moment the window
  // closes, the rest when the stream ends.
  if (params.record.find('/') != std::string::npos)
    throw std::invalid_argument("--record " + params.record +
                                ": a file name in the output folder, without '/'");
  OutputSetOptions options = folderSetOptions();
  options.recording = params.record;
  options.recording_companion = params.record.empty() ? "" : kStatsFile;
  OutputSet set(params.out_dir, "", options, log);

  config = loadAppConfig(params.config_file);
  std::ostringstream effective;
  dumpAppConfig(config, effective);
  log << "Effective configuration (" << params.config_file << "):\n" << effective.str() << "\n";
  const StreamLabels labels{config.input.imu_label.empty() ? "IMU" : config.input.imu_label,
                            config.input.lidar_label.empty() ? "LIDAR" : config.input.lidar_label};

  const std::string state_file = set.finalPath(kStateFile);
  record_path = params.record.empty() ? "" : set.finalPath(params.record);
  set.write(kConfigFile, [&](const std::string& p) {
    writeFileAtomically(p, [&](std::ostream& o) { o << effective.str(); });
  });

  // The recording: written into the staging folder, kept whatever happens.
  std::unique_ptr<RecordWriter> rec;
  if (!record_path.empty()) rec = std::make_unique<RecordWriter>(set.path(params.record), 128);

  std::unique_ptr<net::StreamSource> src =
      source ? std::move(source) : std::make_unique<net::UdpStreamSource>(params.source);
  src->start();
  if (const auto* udp = dynamic_cast<const net::UdpStreamSource*>(src.get())) {
    log << "Listening on UDP " << params.source.address << ":" << udp->port() << " (receive buffer "
        << udp->receiveBufferGranted() << " bytes)\n";
    log.flush();  // a live tool's log is followed as it runs (e.g. tail -f on a file)
    if (on_listening) on_listening(udp->port());
  }

  // The ingest path, as offline: wire items -> record checks -> one session.
  const std::string source_name = "live stream";
  RecordChecker checker(config);
  InitSession session(config, source_name, false);
  const double accel_scale = config.input.imu_accel_in_g ? kGravity : 1.0;
  std::vector<CheckedItem> checked;
  ready_live = false;
  stats_at_ready = {};
  recorded = 0;
  std::string input_error;
  bool data_seen = false, end = false, stopped = false;
  int stopped_by_signal = 0;
  int sessions = 0;
  auto last_data = Clock::now();
  std::vector<net::StreamEvent> events;
  // The moment the session is done while the stream runs: the state is written, or the input
  // error stops the run.
  auto onDone = [&](const net::StreamEvent& e, Clock::time_point t_fed) {
    if (session.failed()) {
      input_error = session.errors().front();
      for (const auto& err : session.errors()) log << "Error: " << err << "\n";
      return;
    }
    const auto t_processed = Clock::now();
    // The state goes out before the map is built (the map is for the outputs at the end).
    const InitResult& r = session.resultBeforeMap();
    set.write(kStateFile, [&](const std::string& p) {
      const StateVerdict v = verdictOf(r, config.core.velocimeter.doppler_sigma);
      writeInitialStateIni(p, r.state, &v);
    });
    set.install({kStateFile});
    const auto t_written = Clock::now();
    latency.queue = secondsBetween(e.received, t_fed);
    latency.estimator = secondsBetween(t_fed, t_processed);
    latency.write = secondsBetween(t_processed, t_written);
    latency.total = secondsBetween(e.received, t_written);
    ready_live = true;
    stats_at_ready = src->stats();
    log << std::fixed << std::setprecision(3) << "State written to " << state_file << ": latency "
        << 1e3 * latency.total << " ms from the receipt of the last needed "
        << "measurement (queue and conversion " << 1e3 * latency.queue << ", estimator "
        << 1e3 * latency.estimator << ", write " << 1e3 * latency.write << ")\n"
        << std::defaultfloat;
    log << (stats_at_ready.anomalies() > 0 ? "Warning: " : "")
        << "anomalies_before_ready = " << stats_at_ready.anomalies() << " ("
        << stats_at_ready.receiver.lost << " datagrams lost, " << stats_at_ready.queue_dropped_imu
        << " IMU samples and " << stats_at_ready.queue_dropped_frames << " frames dropped, "
        << stats_at_ready.receiver.frames_incomplete + stats_at_ready.receiver.frames_inconsistent
        << " frames incomplete or inconsistent)\n";
    log.flush();
    if (params.stop_when_ready) end = true;
  };
  while (!end) {
    if (const int sig = stopSignal()) {
      // The normal way to stop a live tool: the end of the stream, with every output written.
      log << "Stopped by " << signalName(sig) << ": end of the stream\n";
      clearStopRequest();
      stopped_by_signal = sig;
      break;
    }
    events.clear();
    src->poll(events, 0.05);
    const auto now = Clock::now();
    if (!events.empty()) {
      last_data = now;
      if (!data_seen) set.install({kConfigFile});  // the earlier run's outputs go now
      data_seen = true;
    } else if (data_seen && params.idle_timeout > 0 &&
               secondsBetween(last_data, now) > params.idle_timeout) {
      log << "No data for " << params.idle_timeout << " s: end of the stream\n";
      break;
    } else if (!data_seen && params.wait_first > 0 &&
               secondsBetween(t_start, now) > params.wait_first) {
      log << "No data within " << params.wait_first << " s\n";
      break;
    }
    if (params.max_duration > 0 && secondsBetween(t_start, now) > params.max_duration) {
      log << "Maximum duration reached\n";
      break;
    }
    for (auto& e : events) {
      using Kind = net::StreamEvent::Kind;
      if (e.kind == Kind::SessionStart) {
        log << "Sender session " << std::hex << e.session << std::dec
            << (++sessions > 1 ? " (the sender restarted)" : "") << "\n";
        continue;
      }
      if (e.kind == Kind::EndOfStream) {
        log << "End of stream from the sender\n";
        if (params.stop_at_end_of_stream) {
          end = true;
          break;
        }
        continue;
      }
      const auto t_fed = Clock::now();
      const Extrinsics declared = e.frame.extrinsics;
      auto item = itemFromStream(std::move(e), recorded, accel_scale);
      if (!item) continue;
      if (rec) {
        const bool imu = item->kind == IngestItem::Kind::Imu;
        Recorded r;
        r.item.kind = item->kind;
        r.item.stamp_ns = item->stamp_ns;
        r.item.imu = item->imu;
        r.item.imu.accel = e.imu.accel;  // as received (the rawlog decoder applies the unit)
        r.item.frame = item->frame;
        r.label = imu ? labels.imu : labels.lidar;
        r.extrinsics = declared;
        rec->push(std::move(r));
      }
      ++recorded;
      if (stopped || session.done()) continue;
      checked.clear();
      checker.push(std::move(*item), checked);
      for (const auto& c : checked) session.push(c);
      if (session.done()) {
        onDone(e, t_fed);
        if (!input_error.empty()) stopped = true;
      }
      if (end) break;
    }
    if (!input_error.empty()) break;
  }
  src->stop();
  stats = src->stats();
  if (rec) {
    try {
      rec->commit();
    } catch (const std::exception& e) {
      throw OutputError(set.describe(params.record, e.what()));
    }
    rec.reset();
    if (recorded == 0) {
      std::filesystem::remove(set.path(params.record));  // nothing was recorded
    } else {
      log << "Recorded " << recorded << " observations to " << record_path << "\n";
    }
  }
  if (!data_seen) {
    std::ostringstream within;
    if (params.wait_first > 0) within << " within " << params.wait_first << " s";
    throw InputError(source_name + ": no data received" + within.str() +
                     (stopped_by_signal != 0 ? " before " + signalName(stopped_by_signal) : "") +
                     "; nothing written");
  }
  std::ostringstream st;
  net::printStats(st, stats);
  log << "Stream statistics:\n" << st.str();
  set.write(kStatsFile, [&](const std::string& p) {
    writeFileAtomically(p, [&](std::ostream& o) {
      o << "[stream]\n" << st.str() << "recorded            = " << recorded << "\n";
      if (stopped_by_signal != 0)
        o << "stopped_by          = " << signalName(stopped_by_signal) << "\n";
      if (ready_live)
        o << std::setprecision(6) << "latency_total_ms    = " << 1e3 * latency.total
          << "\nlatency_queue_ms    = " << 1e3 * latency.queue
          << "\nlatency_estimator_ms= " << 1e3 * latency.estimator
          << "\nlatency_write_ms    = " << 1e3 * latency.write
          << "\n; stream anomalies before the state was written (data possibly in the window)"
          << "\nanomalies_before_ready = " << stats_at_ready.anomalies()
          << "\nlost_before_ready   = " << stats_at_ready.receiver.lost
          << "\nqueue_dropped_imu_before_ready    = " << stats_at_ready.queue_dropped_imu
          << "\nqueue_dropped_frames_before_ready = " << stats_at_ready.queue_dropped_frames
          << "\n";
    });
  });
  if (stats.anomalies() > 0)
    log << "Warning: " << stats.anomalies()
        << " datagrams or items lost, dropped or rejected (see stream_stats.ini)\n";
  // An input error: the recording and its statistics are kept (abandon() installs them), the
  // rest goes.
  if (!input_error.empty()) throw InputError(input_error);

  if (!session.done()) {
    checked.clear();
    checker.finish(checked);
    for (const auto& c : checked) session.push(c);
    session.finish();
    if (session.failed()) {
      for (const auto& err : session.errors()) log << "Error: " << err << "\n";
      throw InputError(session.errors().front());
    }
    if (!session.ready()) throw InputError(session.endOfDataReason());
    set.write(kStateFile, [&](const std::string& p) {
      const StateVerdict v = verdictOf(session.result(), config.core.velocimeter.doppler_sigma);
      writeInitialStateIni(p, session.result().state, &v);
    });
  }
  for (const auto& w : session.warnings()) log << "Warning: " << w << "\n";
  if (session.ready() && session.result().state.ok()) {
    printVerdict(log, verdictOf(session.result(), config.core.velocimeter.doppler_sigma));
    for (const auto& w : session.result().state.warnings) log << "  warning: " << w << "\n";
  }
  result = session.result();
  if (stopped_by_signal != 0 && !ready_live)
    log << "The stream was stopped by " << signalName(stopped_by_signal)
        << " before the window closed\n";
  writeResultFiles(set, "", config.output, result, {});
  set.commit();
  log << "Initialization: " << toString(result.state.status)
      << (result.state.message.empty() ? "" : " (" + result.state.message + ")") << "\n";
  return result.state.ok() ? 0 : 3;
}

}  // namespace freeinit::mrpt_plugins
