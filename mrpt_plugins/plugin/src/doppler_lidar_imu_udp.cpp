// The only translation unit that includes mrpt/hwdrivers.
#include <freeinit/io/atomic_file.h>
#include <freeinit/io/config_section.h>
#include <freeinit/mrpt_plugins/doppler_lidar_imu_udp.h>
#include <freeinit/mrpt_plugins/register.h>
#include <mrpt/config/CConfigFile.h>
#include <mrpt/core/initializer.h>

#include <iostream>
#include <sstream>
#include <stdexcept>

IMPLEMENTS_GENERIC_SENSOR(CDopplerLidarImuUdp, freeinit::mrpt_plugins)

namespace freeinit::mrpt_plugins {

CDopplerLidarImuUdp::~CDopplerLidarImuUdp() {
  if (!source_) return;
  source_->stop();
  try {
    report(true);
  } catch (const std::exception& e) {
    std::cerr << "[" << m_sensorLabel << "] " << e.what() << "\n";
  }
}

const config::Section<UdpDriverParams>& udpDriverSection() {
  using config::between;
  using P = UdpDriverParams;
  static const auto s =
      config::Section<P>("DOPPLER_LIDAR_IMU",
                         "a Doppler LiDAR + IMU streaming the Free-Init wire format over UDP "
                         "(driver = CDopplerLidarImuUdp; the section name is the sensor's)")
          .text(
              "listen_address", [](auto& x) -> auto& { return x.source.address; },
              "local IPv4 address to listen on (0.0.0.0: every interface)", true)
          .number(
              "port", [](auto& x) -> auto& { return x.source.port; }, "-", between(0, 65535),
              "UDP port (0: any free port)")
          .text(
              "imu_label", [](auto& x) -> auto& { return x.labels.imu; },
              "sensorLabel of the CObservationIMU", true)
          .text(
              "lidar_label", [](auto& x) -> auto& { return x.labels.lidar; },
              "sensorLabel of the CObservationPointCloud", true)
          .number(
              "receive_buffer_bytes", [](auto& x) -> auto& { return x.source.receive_buffer; },
              "bytes", between(1024, 1 << 30), "socket receive buffer asked for")
          .number(
              "max_queued_imu", [](auto& x) -> auto& { return x.source.max_queued_imu; }, "-",
              between(1, 1e7), "IMU samples queued towards the grabber (drops are counted)")
          .number(
              "max_queued_frames", [](auto& x) -> auto& { return x.source.max_queued_frames; }, "-",
              between(1, 1e5), "frames queued towards the grabber (drops are counted)")
          .number(
              "reorder_window", [](auto& x) -> auto& { return x.source.receiver.reorder_window; },
              "datagrams", between(1, 1e6), "held while waiting for a missing one")
          .scaled(
              "reorder_timeout_ms",
              [](auto& x) -> auto& { return x.source.receiver.reorder_timeout; }, "ms", 1000,
              between(0, 60000), "longest wait for a missing datagram")
          .scaled(
              "frame_timeout_ms", [](auto& x) -> auto& { return x.source.receiver.frame_timeout; },
              "ms", 1000, config::aboveUpTo(0, 60000),
              "an incomplete frame is dropped (and counted) after this long without a chunk")
          .number("stats_period_s", &P::stats_period, "s", between(0, 86400),
                  "statistics on stdout every this long (0: only at the end)")
          .text("stats_file", &P::stats_file,
                "write the final statistics to this INI file (empty: none)")
          .foreign({"driver", "process_rate", "max_queue_len", "grab_decimation", "sensorLabel",
                    "pose_x", "pose_y", "pose_z", "pose_yaw", "pose_pitch", "pose_roll",
                    "external_images_format", "external_images_jpeg_quality"});
  return s;
}

void CDopplerLidarImuUdp::loadConfig_sensorSpecific(const mrpt::config::CConfigFileBase& cfg,
                                                    const std::string& section) {
  // The section through the project's strict loader: from the file itself when rawlog-grabber
  // read one (lines and duplicated keys are then known), else from MRPT's parsed keys.
  config::IniFile ini;
  const auto* file = dynamic_cast<const mrpt::config::CConfigFile*>(&cfg);
  if (file && !file->getAssociatedFile().empty()) {
    ini = config::IniFile::load(file->getAssociatedFile(), {{section}});
  } else {
    ini = config::IniFile("rawlog-grabber configuration");
    config::IniSection sec;
    sec.name = section;
    std::vector<std::string> keys;
    cfg.getAllKeys(section, keys);
    for (const auto& k : keys) sec.entries.push_back({k, cfg.read_string(section, k, ""), 0, ""});
    ini.add(std::move(sec));
  }
  UdpDriverParams p;
  p.source = params_;
  p.labels = labels_;
  p.stats_period = stats_period_;
  p.stats_file = stats_file_;
  try {
    udpDriverSection().load(ini, section, p);  // the sensor's section, whatever its name
  } catch (const config::ConfigError& e) {
    // rawlog-grabber rethrows this as an MRPT exception, which splits the message at its
    // brackets: the user sees the one line here too.
    std::cerr << "CDopplerLidarImuUdp: " << e.what() << "\n";
    throw;
  }
  params_ = p.source;
  labels_ = p.labels;
  stats_period_ = p.stats_period;
  stats_file_ = p.stats_file;
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

}  // namespace freeinit::mrpt_plugins

// Registers the driver with rawlog-grabber's factory when the plugin library is loaded.
MRPT_INITIALIZER(freeinit_register_grabber_drivers) {
  freeinit::mrpt_plugins::CDopplerLidarImuUdp::doRegister();
}
