// The only translation unit that includes mrpt/hwdrivers.
#include <freeinit/atomic_file.h>
#include <freeinit/mrpt/CDopplerLidarImuUdp.h>
#include <freeinit/mrpt/register.h>
#include <mrpt/core/initializer.h>

#include <iostream>
#include <sstream>
#include <stdexcept>

IMPLEMENTS_GENERIC_SENSOR(CDopplerLidarImuUdp, freeinit::mrpt_glue)

namespace freeinit::mrpt_glue {

CDopplerLidarImuUdp::~CDopplerLidarImuUdp() {
  if (!source_) return;
  source_->stop();
  try {
    report(true);
  } catch (const std::exception& e) {
    std::cerr << "[" << m_sensorLabel << "] " << e.what() << "\n";
  }
}

void CDopplerLidarImuUdp::loadConfig_sensorSpecific(const mrpt::config::CConfigFileBase& cfg,
                                                    const std::string& section) {
  auto fail = [&](const std::string& key, const std::string& why) {
    throw std::invalid_argument("[" + section + "] " + key + ": " + why);
  };
  params_.address = cfg.read_string(section, "listen_address", params_.address);
  const int port = cfg.read_int(section, "port", params_.port);
  if (port < 0 || port > 65535) fail("port", "must be in 0..65535");
  params_.port = static_cast<std::uint16_t>(port);
  labels_.imu = cfg.read_string(section, "imu_label", labels_.imu);
  labels_.lidar = cfg.read_string(section, "lidar_label", labels_.lidar);
  params_.receive_buffer = cfg.read_int(section, "receive_buffer_bytes", params_.receive_buffer);
  const int q_imu =
      cfg.read_int(section, "max_queued_imu", static_cast<int>(params_.max_queued_imu));
  const int q_frames =
      cfg.read_int(section, "max_queued_frames", static_cast<int>(params_.max_queued_frames));
  const int window =
      cfg.read_int(section, "reorder_window", static_cast<int>(params_.receiver.reorder_window));
  if (q_imu < 1) fail("max_queued_imu", "must be >= 1");
  if (q_frames < 1) fail("max_queued_frames", "must be >= 1");
  if (window < 1) fail("reorder_window", "must be >= 1");
  params_.max_queued_imu = static_cast<std::size_t>(q_imu);
  params_.max_queued_frames = static_cast<std::size_t>(q_frames);
  params_.receiver.reorder_window = static_cast<std::size_t>(window);
  params_.receiver.reorder_timeout =
      1e-3 * cfg.read_double(section, "reorder_timeout_ms", 1e3 * params_.receiver.reorder_timeout);
  params_.receiver.frame_timeout =
      1e-3 * cfg.read_double(section, "frame_timeout_ms", 1e3 * params_.receiver.frame_timeout);
  if (!(params_.receiver.reorder_timeout >= 0)) fail("reorder_timeout_ms", "must be >= 0");
  if (!(params_.receiver.frame_timeout > 0)) fail("frame_timeout_ms", "must be > 0");
  stats_period_ = cfg.read_double(section, "stats_period_s", stats_period_);
  stats_file_ = cfg.read_string(section, "stats_file", stats_file_);
}

void CDopplerLidarImuUdp::initialize() {
  registerClasses();
  if (!source_) source_ = std::make_unique<net::UdpStreamSource>(params_);
  try {
    source_->start();
  } catch (const std::exception& e) {
    m_state = ssError;
    throw std::runtime_error("[" + m_sensorLabel + "] " + e.what());
  }
  if (const auto* udp = dynamic_cast<const net::UdpStreamSource*>(source_.get()))
    std::cout << "[" << m_sensorLabel << "] listening for the Doppler LiDAR + IMU stream on UDP "
              << params_.address << ":" << udp->port() << "\n";  // the bound port (port = 0)
  last_report_ = std::chrono::steady_clock::now();
  m_state = ssWorking;
}

void CDopplerLidarImuUdp::doProcess() {
  if (!source_) return;
  events_.clear();
  source_->poll(events_, 0.0);
  std::vector<mrpt::serialization::CSerializable::Ptr> batch;
  for (const auto& e : events_) {
    if (auto obs = toObservation(e, labels_)) {
      batch.push_back(obs);
    } else if (e.kind == net::StreamEvent::Kind::SessionStart) {
      std::cout << "[" << m_sensorLabel << "] sender session " << std::hex << e.session << std::dec
                << "\n";
    } else if (e.kind == net::StreamEvent::Kind::EndOfStream) {
      std::cout << "[" << m_sensorLabel << "] end of stream from the sender\n";
    }
  }
  // One observation at a time: a block would count as one for grab_decimation.
  for (const auto& o : batch) appendObservation(o);
  if (stats_period_ > 0 && std::chrono::steady_clock::now() - last_report_ >
                               std::chrono::duration<double>(stats_period_))
    report(false);
}

net::SourceStats CDopplerLidarImuUdp::stats() const {
  return source_ ? source_->stats() : net::SourceStats{};
}

void CDopplerLidarImuUdp::report(bool final) {
  last_report_ = std::chrono::steady_clock::now();
  const net::SourceStats s = stats();
  std::cout << "[" << m_sensorLabel << "] " << (final ? "final: " : "") << s.receiver.imu_samples
            << " IMU samples, " << s.receiver.frames << " frames, " << s.receiver.datagrams
            << " datagrams; anomalies: " << s.anomalies() << " (lost " << s.receiver.lost
            << ", malformed " << s.receiver.malformed << ", duplicates " << s.receiver.duplicates
            << ", incomplete frames " << s.receiver.frames_incomplete << ", queue drops "
            << s.queue_dropped_imu + s.queue_dropped_frames << ")\n";
  if (final && !stats_file_.empty()) {
    writeFileAtomically(stats_file_, [&](std::ostream& o) {
      o << "[stream]\n";
      net::printStats(o, s);
    });
  }
}

}  // namespace freeinit::mrpt_glue

// Registers the driver with rawlog-grabber's factory when the plugin library is loaded.
MRPT_INITIALIZER(freeinit_register_grabber_drivers) {
  freeinit::mrpt_glue::CDopplerLidarImuUdp::doRegister();
}
