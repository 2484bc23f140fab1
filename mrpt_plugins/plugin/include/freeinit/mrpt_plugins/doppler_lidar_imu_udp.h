// rawlog-grabber sensor driver for a Doppler LiDAR + IMU streaming the Free-Init wire format over
// UDP (docs/wire_format.md). Emits CObservationIMU and CObservationPointCloud (holding a
// CPointsMapDoppler), the observations `freeinit` reads. Load it with
//   rawlog-grabber -p build/mrpt_plugins/libfreeinit_mrpt_plugins.so
//   ini/rawlog_grabber_doppler_udp.ini
// INI section keys (udpDriverSection(); besides rawlog-grabber's own driver, process_rate,
// max_queue_len, grab_decimation, sensorLabel, pose_*): listen_address (127.0.0.1), port (47800),
// imu_label (IMU), lidar_label (LIDAR), receive_buffer_bytes (16777216), max_queued_imu (4000),
// max_queued_frames (16), reorder_window (1024 datagrams), reorder_timeout_ms (50),
// frame_timeout_ms (500), stats_period_s (5; 0 = only at the end), stats_file ("" = none;
// written at the end). Any other key is an error.
// The data source sits behind net::StreamSource: a vendor SDK can replace the UDP receiver.
#pragma once

#include <freeinit/mrpt_plugins/stream_conversions.h>
#include <freeinit/net/stream_source.h>
#include <mrpt/hwdrivers/CGenericSensor.h>

#include <chrono>
#include <memory>
#include <string>

namespace freeinit::config {
template <class S>
class Section;
}  // namespace freeinit::config

namespace freeinit::mrpt_plugins {

/// The driver's keys of its rawlog-grabber INI section.
struct UdpDriverParams {
  net::UdpSourceParams source;
  StreamLabels labels;
  double stats_period = 5;  ///< [s] statistics on stdout every this long (0: only at the end)
  std::string stats_file;   ///< final statistics written to this INI file ("" = none)
};
const config::Section<UdpDriverParams>& udpDriverSection();

class CDopplerLidarImuUdp : public mrpt::hwdrivers::CGenericSensor {
  DEFINE_GENERIC_SENSOR(CDopplerLidarImuUdp)

 public:
  CDopplerLidarImuUdp() = default;
  ~CDopplerLidarImuUdp() override;

  /// Opens the source (binds the UDP port). Throws naming the address if it cannot.
  void initialize() override;
  /// Moves what the source received into the observation queue.
  void doProcess() override;

  /// Replaces the UDP receiver by another source (before initialize()).
  void setSource(std::unique_ptr<net::StreamSource> source) { source_ = std::move(source); }
  net::SourceStats stats() const;

 protected:
  void loadConfig_sensorSpecific(const mrpt::config::CConfigFileBase& cfg,
                                 const std::string& section) override;

 private:
  void report(bool final);

  net::UdpSourceParams params_;
  StreamLabels labels_;
  double stats_period_ = 5;
  std::string stats_file_;
  std::unique_ptr<net::StreamSource> source_;
  std::chrono::steady_clock::time_point last_report_;
  std::vector<net::StreamEvent> events_;
};

}  // namespace freeinit::mrpt_plugins
