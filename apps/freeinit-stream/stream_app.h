// freeinit-stream: plays a recording as a live Doppler LiDAR + IMU stream in the wire format
// (docs/wire_format.md) to a UDP address, in real time or faster, optionally with network faults.
// The recording is a simulator preset or a rawlog (read by our reader and checked by the offline
// app's validator: a rawlog it refuses is refused here too). Each IMU
// sample is sent at its timestamp, each chunk of a frame when its last point was measured
// (stamp + time offset), as a scanning sensor streams them.
#pragma once

#include <freeinit/net/stream_sender.h>

#include <cstdint>
#include <iosfwd>
#include <string>

namespace freeinit::apps {

struct StreamAppParams {
  std::string rawlog;              ///< play this rawlog; empty: simulate `preset`
  std::string imu_label;           ///< rawlog: the IMU's sensorLabel ("" = any)
  std::string lidar_label;         ///< rawlog: the LiDAR's sensorLabel ("" = any)
  bool imu_accel_in_g = false;     ///< rawlog: accelerations in g (sent as m/s^2); checked
  std::string preset = "dyna_01";  ///< freeinit::sim preset
  std::uint64_t seed = 1;
  double duration = 0;       ///< [s] simulated duration (0: the preset's)
  int points_per_frame = 0;  ///< simulated points per frame (0: the preset's)
  std::string address = "127.0.0.1";
  std::uint16_t port = 47800;
  std::size_t max_datagram = 8192;  ///< [bytes] 1472 for an Ethernet MTU
  double speed = 1.0;               ///< playback speed factor; 0: as fast as possible (a burst)
  double wait_listener = 0;         ///< [s] wait up to this long for a local listener on the port
  net::FaultParams faults;
  double restart_at = -1;  ///< [s] into the stream: the sender restarts (new session)
  int garbage = 0;         ///< random non-packets sent half-way
  bool end_marker = true;  ///< send the end-of-stream marker at the end
};

class StreamApp {
 public:
  StreamAppParams params;
  /// Throws on bad input; returns when everything was sent.
  void run(std::ostream& log);
  /// The command line (`main` of freeinit-stream): parses it, runs, returns the exit code.
  static int main(int argc, char** argv);
  net::SenderStats stats;
  std::size_t imu_sent = 0, frames_sent = 0;
};

}  // namespace freeinit::apps
