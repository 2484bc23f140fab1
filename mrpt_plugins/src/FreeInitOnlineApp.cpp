#include <freeinit/mrpt/FreeInitApp.h>
#include <freeinit/mrpt/FreeInitObservationHandler.h>
#include <freeinit/mrpt/FreeInitOnlineApp.h>
#include <freeinit/mrpt/output_writers.h>
#include <freeinit/mrpt/rawlog_reader.h>
#include <freeinit/mrpt/register.h>
#include <freeinit/mrpt/stream_conversions.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/serialization/CArchive.h>

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

namespace freeinit::mrpt_glue {
namespace {

using Clock = std::chrono::steady_clock;
double secondsBetween(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

// Serializes and compresses the recording in its own thread, so that writing a large frame does
// not delay the estimator. The queue is bounded: when the disk cannot keep up, push() waits, and
// the source's bounded queue then drops (and counts) instead.
class RecordWriter {
 public:
  RecordWriter(const std::string& path, std::size_t max_queued) : max_queued_(max_queued) {
    if (!file_.open(path)) throw std::runtime_error(path + ": cannot create");
    thread_ = std::thread([this] { loop(); });
  }
  ~RecordWriter() {
    try {
      close();
    } catch (const std::exception&) {
      // Only reached while unwinding from another error, which is the one reported.
    }
  }

  void push(mrpt::obs::CObservation::Ptr obs) {
    std::unique_lock<std::mutex> lock(mutex_);
    room_.wait(lock, [&] { return queue_.size() < max_queued_ || !error_.empty(); });
    if (!error_.empty()) throw std::runtime_error(error_);
    queue_.push_back(std::move(obs));
    ready_.notify_one();
  }
  /// Writes what is queued and closes the file; throws if writing failed.
  void close() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      closing_ = true;
    }
    ready_.notify_one();
    if (thread_.joinable()) thread_.join();
    file_.close();
    if (!error_.empty()) throw std::runtime_error(error_);
  }

 private:
  void loop() {
    auto arch = mrpt::serialization::archiveFrom(file_);
    for (;;) {
      mrpt::obs::CObservation::Ptr obs;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        ready_.wait(lock, [&] { return !queue_.empty() || closing_; });
        if (queue_.empty()) return;
        obs = std::move(queue_.front());
        queue_.pop_front();
      }
      room_.notify_one();
      try {
        arch << *obs;
      } catch (const std::exception& e) {
        std::lock_guard<std::mutex> lock(mutex_);
        error_ = std::string("recording: ") + e.what();
        room_.notify_all();
        return;
      }
    }
  }

  mrpt::io::CFileGZOutputStream file_;
  std::size_t max_queued_;
  std::mutex mutex_;
  std::condition_variable ready_, room_;
  std::deque<mrpt::obs::CObservation::Ptr> queue_;
  bool closing_ = false;
  std::string error_;
  std::thread thread_;
};

}  // namespace

int FreeInitOnlineApp::run(std::ostream& log) {
  registerClasses();
  const auto t_start = Clock::now();

  config = loadAppConfig(params.config_file);
  std::ostringstream effective;
  dumpAppConfig(config, effective);
  log << "Effective configuration (" << params.config_file << "):\n" << effective.str() << "\n";
  const StreamLabels labels{config.input.imu_label.empty() ? "IMU" : config.input.imu_label,
                            config.input.lidar_label.empty() ? "LIDAR" : config.input.lidar_label};

  const std::filesystem::path out(params.out_dir);
  std::filesystem::create_directories(out);
  auto file = [&](const char* name) { return (out / name).string(); };
  writeFileAtomically(file("effective_config.ini"), [&](std::ostream& o) { o << effective.str(); });
  const std::string state_file = file("initial_state.ini");
  std::remove(state_file.c_str());  // a state from an earlier run must not pass for this one

  // The recording: written to a temporary name, renamed when closed.
  record_path = params.record.empty() ? "" : (out / params.record).string();
  std::unique_ptr<RecordWriter> rec;
  if (!record_path.empty()) rec = std::make_unique<RecordWriter>(record_path + ".tmp", 128);

  std::unique_ptr<net::StreamSource> src =
      source ? std::move(source) : std::make_unique<net::UdpStreamSource>(params.source);
  src->start();
  if (const auto* udp = dynamic_cast<const net::UdpStreamSource*>(src.get())) {
    log << "Listening on UDP " << params.source.address << ":" << udp->port() << " (receive buffer "
        << udp->receiveBufferGranted() << " bytes)\n";
    if (on_listening) on_listening(udp->port());
  }

  FreeInitObservationHandler handler(config);
  ready_live = false;
  recorded = 0;
  std::string input_error;
  bool data_seen = false, end = false;
  int sessions = 0;
  auto last_data = Clock::now();
  std::vector<net::StreamEvent> events;
  while (!end) {
    events.clear();
    src->poll(events, 0.05);
    const auto now = Clock::now();
    if (!events.empty()) {
      last_data = now;
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
    for (const auto& e : events) {
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
      const auto obs = toObservation(e, labels);
      if (input_error.empty() && !handler.ready()) {
        const auto t_fed = Clock::now();
        try {
          handler.process(obs);
        } catch (const std::exception& ex) {
          input_error = "live stream, observation " + std::to_string(recorded) + ": " + ex.what();
          log << "Error: " << input_error << "\n";
        }
        if (handler.ready()) {
          const auto t_processed = Clock::now();
          writeInitialStateIni(state_file, handler.result().state);
          const auto t_written = Clock::now();
          latency.queue = secondsBetween(e.received, t_fed);
          latency.estimator = secondsBetween(t_fed, t_processed);
          latency.write = secondsBetween(t_processed, t_written);
          latency.total = secondsBetween(e.received, t_written);
          ready_live = true;
          log << std::fixed << std::setprecision(3) << "State written to " << state_file
              << ": latency " << 1e3 * latency.total << " ms from the receipt of the last needed "
              << "measurement (queue and conversion " << 1e3 * latency.queue << ", estimator "
              << 1e3 * latency.estimator << ", write " << 1e3 * latency.write << ")\n"
              << std::defaultfloat;
          if (params.stop_when_ready) end = true;
        }
      }
      if (rec) rec->push(obs);
      ++recorded;
      if (end) break;
    }
    if (!input_error.empty()) break;
  }
  src->stop();
  stats = src->stats();
  if (rec) {
    rec->close();
    rec.reset();
    std::filesystem::rename(record_path + ".tmp", record_path);
    log << "Recorded " << recorded << " observations to " << record_path << "\n";
  }
  std::ostringstream st;
  net::printStats(st, stats);
  log << "Stream statistics:\n" << st.str();
  writeFileAtomically(file("stream_stats.ini"), [&](std::ostream& o) {
    o << "[stream]\n" << st.str() << "recorded            = " << recorded << "\n";
    if (ready_live)
      o << std::setprecision(6) << "latency_total_ms    = " << 1e3 * latency.total
        << "\nlatency_queue_ms    = " << 1e3 * latency.queue
        << "\nlatency_estimator_ms= " << 1e3 * latency.estimator
        << "\nlatency_write_ms    = " << 1e3 * latency.write << "\n";
  });
  if (stats.anomalies() > 0)
    log << "Warning: " << stats.anomalies()
        << " datagrams or items lost, dropped or rejected (see stream_stats.ini)\n";
  if (!input_error.empty()) throw InputError(input_error);

  if (!handler.ready()) {
    handler.finish();
    writeInitialStateIni(state_file, handler.result().state);
  }
  result = handler.result();
  writeResultFiles(params.out_dir, config.output, result, {});
  log << "Initialization: " << toString(result.state.status)
      << (result.state.message.empty() ? "" : " (" + result.state.message + ")") << "\n";
  return result.state.ok() ? 0 : 3;
}

}  // namespace freeinit::mrpt_glue
