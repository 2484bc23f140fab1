#include "stream_app.h"

#include <freeinit/app_support/checked_recording.h>
#include <freeinit/app_support/command_line.h>
#include <freeinit/mrpt_plugins/conversions.h>
#include <freeinit/mrpt_plugins/stream_conversions.h>
#include <freeinit/net/udp_socket.h>
#include <freeinit/net/wire_format.h>
#include <freeinit/sim/simulator.h>

#include <algorithm>
#include <chrono>
#include <iostream>
#include <ostream>
#include <stdexcept>
#include <thread>

namespace freeinit::apps {
namespace {

// What is played: IMU samples and frames, each stream in time order.
struct Messages {
  std::vector<net::ImuMessage> imu;
  std::vector<net::FrameMessage> frames;
};

// One datagram to send at `send_ns` (stream time): an IMU sample or one chunk of a frame.
struct Slot {
  std::int64_t send_ns = 0;
  bool is_chunk = false;
  std::size_t index = 0;  ///< into Messages::imu or Messages::frames
  std::size_t chunk = 0;
};

// The rawlog through the ingest path (the same labels, extrinsics from sensorPose, unit and
// Doppler checks as freeinit), with the exact stamps of the observations.
Messages fromRawlog(const StreamAppParams& p) {
  app_support::AppConfig cfg;
  cfg.input.imu_label = p.imu_label;
  cfg.input.lidar_label = p.lidar_label;
  cfg.input.imu_accel_in_g = p.imu_accel_in_g;
  cfg.input.min_imu_rate = 0;    // the receiver judges the rate
  cfg.core.window.duration = 0;  // any length can be streamed
  app_support::CheckedRecording in = app_support::readRecording(p.rawlog, cfg);
  if (in.imu_stamp_ns.size() != in.imu.size() || in.frame_stamp_ns.size() != in.frames.size())
    throw mrpt_plugins::InputError(p.rawlog +
                                   ": timestamps outside the stream's range 1970 .. 2116");
  const Extrinsics extrinsics = in.sensor_pose_extrinsics.value_or(Extrinsics{});
  Messages m;
  m.imu.reserve(in.imu.size());
  for (std::size_t i = 0; i < in.imu.size(); ++i) {
    net::ImuMessage msg;
    msg.stamp_ns = in.imu_stamp_ns[i];
    msg.gyro = in.imu[i].gyro;
    msg.accel = in.imu[i].accel;  // in m/s^2 (the reader applied the declared unit)
    m.imu.push_back(msg);
  }
  m.frames.reserve(in.frames.size());
  for (std::size_t i = 0; i < in.frames.size(); ++i) {
    net::FrameMessage msg;
    msg.stamp_ns = in.frame_stamp_ns[i];
    msg.extrinsics = extrinsics;
    msg.points = std::move(in.frames[i].points);
    m.frames.push_back(std::move(msg));
  }
  return m;
}

// The simulated recording, through the same observations freeinit-sim writes (so that stamps
// are on MRPT's 100 ns clock as in a rawlog).
Messages fromSimulator(const StreamAppParams& p) {
  sim::ScenarioConfig sc = sim::preset(p.preset, p.seed);
  if (p.duration > 0) sc.duration = p.duration;
  if (p.points_per_frame > 0) sc.points_per_frame = p.points_per_frame;
  const sim::Recording rec = sim::simulate(sc);
  Messages m;
  for (const auto& s : rec.imu)
    m.imu.push_back(mrpt_plugins::imuMessage(*mrpt_plugins::imuToObservation(s, "IMU")));
  for (const auto& f : rec.frames)
    m.frames.push_back(mrpt_plugins::frameMessage(
        *mrpt_plugins::frameToObservation(f, rec.extrinsics, "LIDAR"), rec.extrinsics));
  return m;
}

// Each IMU sample at its stamp; each chunk of a frame when its last point was measured (points
// are in time order), as a scanning sensor streams them.
std::vector<Slot> schedule(const Messages& m, std::size_t max_datagram) {
  std::vector<Slot> slots;
  for (std::size_t i = 0; i < m.imu.size(); ++i) slots.push_back({m.imu[i].stamp_ns, false, i, 0});
  const std::size_t per_chunk = net::pointsPerChunk(max_datagram);
  for (std::size_t i = 0; i < m.frames.size(); ++i) {
    const auto& f = m.frames[i];
    const std::size_t chunks = net::chunkCount(f.points.size(), max_datagram);
    float last = 0;
    for (std::size_t c = 0; c < chunks; ++c) {
      for (std::size_t k = c * per_chunk; k < std::min(f.points.size(), (c + 1) * per_chunk); ++k)
        last = std::max(last, f.points[k].time_offset);
      slots.push_back(
          {f.stamp_ns + static_cast<std::int64_t>(static_cast<double>(last) * 1e9), true, i, c});
    }
  }
  // By send time; IMU first on ties; chunks of a frame stay in order.
  std::stable_sort(slots.begin(), slots.end(), [](const Slot& a, const Slot& b) {
    return a.send_ns != b.send_ns ? a.send_ns < b.send_ns : (!a.is_chunk && b.is_chunk);
  });
  return slots;
}

}  // namespace

void StreamApp::run(std::ostream& log) {
  if (!(params.speed >= 0)) throw std::invalid_argument("speed must be >= 0");
  Messages m = params.rawlog.empty() ? fromSimulator(params) : fromRawlog(params);
  if (m.imu.empty() && m.frames.empty()) throw std::invalid_argument("nothing to send");
  for (std::size_t i = 0; i < m.frames.size(); ++i)
    m.frames[i].frame_id = static_cast<std::uint32_t>(i);
  const std::vector<Slot> slots = schedule(m, params.max_datagram);
  const double span = 1e-9 * static_cast<double>(slots.back().send_ns - slots.front().send_ns);
  log << "Streaming " << (params.rawlog.empty() ? "preset " + params.preset : params.rawlog) << ": "
      << m.imu.size() << " IMU samples and " << m.frames.size() << " frames (" << slots.size()
      << " datagrams) over " << span << " s to UDP " << params.address << ":" << params.port
      << " at " << (params.speed > 0 ? std::to_string(params.speed) + "x real time" : "full speed")
      << "\n";

  if (params.wait_listener > 0) {
    const auto until =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(params.wait_listener);
    while (!net::udpPortInUse(params.address, params.port)) {
      if (std::chrono::steady_clock::now() > until)
        throw std::runtime_error("nothing listens on UDP " + params.address + ":" +
                                 std::to_string(params.port) + " after " +
                                 std::to_string(params.wait_listener) + " s");
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }

  net::StreamSender sender(params.address, params.port, params.max_datagram, params.faults);
  const auto t0 = std::chrono::steady_clock::now();
  const std::int64_t first = slots.front().send_ns;
  bool restarted = false, garbage_sent = false;
  imu_sent = frames_sent = 0;
  for (std::size_t i = 0; i < slots.size(); ++i) {
    const Slot& slot = slots[i];
    const double t_stream = 1e-9 * static_cast<double>(slot.send_ns - first);
    if (params.speed > 0)
      std::this_thread::sleep_until(t0 +
                                    std::chrono::duration_cast<std::chrono::nanoseconds>(
                                        std::chrono::duration<double>(t_stream / params.speed)));
    // A restart mid-frame loses the frame in flight, as a real sender restart would.
    if (!restarted && params.restart_at >= 0 && t_stream >= params.restart_at) {
      sender.restart();
      restarted = true;
      log << "Sender restarted at " << t_stream << " s (new session)\n";
    }
    if (!garbage_sent && params.garbage > 0 && 2 * i >= slots.size()) {
      sender.sendGarbage(params.garbage);
      garbage_sent = true;
    }
    if (slot.is_chunk) {
      const auto& f = m.frames[slot.index];
      sender.sendFrameChunk(f, slot.chunk);
      if (slot.chunk + 1 == net::chunkCount(f.points.size(), params.max_datagram)) ++frames_sent;
    } else {
      sender.sendImu(m.imu[slot.index]);
      ++imu_sent;
    }
  }
  if (params.end_marker) sender.sendEndOfStream();
  sender.flush();
  stats = sender.stats();
  log << "Sent " << imu_sent << " IMU samples and " << frames_sent << " frames in "
      << stats.datagrams << " datagrams (" << stats.bytes / 1e6 << " MB) in "
      << std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() << " s\n";
  if (stats.dropped + stats.duplicated + stats.reordered + stats.corrupted + stats.truncated +
          stats.garbage >
      0)
    log << "Injected faults: " << stats.dropped << " dropped, " << stats.duplicated
        << " duplicated, " << stats.reordered << " reordered, " << stats.corrupted << " corrupted, "
        << stats.truncated << " truncated, " << stats.garbage << " garbage datagrams\n";
  if (stats.refused > 0)
    log << "Warning: " << stats.refused << " datagrams refused by the system (no listener?)\n";
}

int StreamApp::main(int argc, char** argv) {
  namespace range = freeinit::config;
  using range::between;
  app_support::CommandLine cli(
      "freeinit-stream",
      "plays a simulator preset or a rawlog as a live Doppler LiDAR + IMU "
      "stream (docs/wire_format.md) over UDP, in real time or faster, with "
      "optional faults");
  const auto& rawlog = cli.text("i", "rawlog", "rawlog to play", "", "FILE", "none: simulate");
  const auto& preset =
      cli.choice("P", "preset", "simulator preset", "dyna_01", freeinit::sim::presetNames());
  const auto& seed = cli.integer("s", "seed", "simulator seed", 1, 0, 4294967295LL, "N");
  const auto& duration =
      cli.number("d", "duration", "simulated seconds (0: the preset's)", 0, between(0, 3600), "S");
  const auto& points = cli.integer(
      "n", "points-per-frame", "simulated points per frame (0: the preset's)", 0, 0, 10000000, "N");
  const auto& address = cli.text("a", "address", "destination IPv4 address", "127.0.0.1", "IP");
  const auto& port = cli.integer("p", "port", "destination UDP port", 47800, 1, 65535, "N");
  const auto& mtu = cli.integer("m", "max-datagram", "bytes per datagram (1472 for Ethernet)", 8192,
                                static_cast<long long>(freeinit::net::kMinDatagram),
                                static_cast<long long>(freeinit::net::kMaxDatagram), "B");
  const auto& speed = cli.number("x", "speed", "playback speed factor (0: as fast as possible)",
                                 1.0, between(0, 1000), "F");
  const auto& wait =
      cli.number("w", "wait-listener", "wait up to S s for a listener on the local port", 0,
                 between(0, 3600), "S");
  const auto& drop =
      cli.number("", "drop", "probability a datagram is lost", 0, between(0, 1), "P");
  const auto& dup =
      cli.number("", "duplicate", "probability a datagram is sent twice", 0, between(0, 1), "P");
  const auto& reorder =
      cli.number("", "reorder", "probability a datagram is sent late", 0, between(0, 1), "P");
  const auto& corrupt =
      cli.number("", "corrupt", "probability a byte is flipped", 0, between(0, 1), "P");
  const auto& truncate =
      cli.number("", "truncate", "probability a datagram is cut short", 0, between(0, 1), "P");
  const auto& fault_seed =
      cli.integer("", "fault-seed", "seed of the fault draws", 1, 0, 4294967295LL, "N");
  const auto& restart = cli.number("", "restart-at", "restart the sender S s into the stream", -1,
                                   between(0, 1e6), "S", "none");
  const auto& garbage =
      cli.integer("", "garbage", "N random non-packets half-way", 0, 0, 1000000, "N");
  const auto& no_end = cli.flag("", "no-end-marker", "do not send the end-of-stream marker");
  const auto& in_g =
      cli.flag("", "imu-accel-in-g", "the rawlog's accelerations are in g (sent as m/s^2)");
  if (const auto code = cli.parse(argc, argv)) return *code;
  return app_support::runMain(cli.program(), [&] {
    StreamApp app;
    auto& p = app.params;
    p.rawlog = rawlog.value;
    p.preset = preset.value;
    p.seed = static_cast<std::uint64_t>(seed.value);
    p.duration = duration.value;
    p.points_per_frame = static_cast<int>(points.value);
    p.address = address.value;
    p.port = static_cast<std::uint16_t>(port.value);
    p.max_datagram = static_cast<std::size_t>(mtu.value);
    p.speed = speed.value;
    p.wait_listener = wait.value;
    p.faults.drop = drop.value;
    p.faults.duplicate = dup.value;
    p.faults.reorder = reorder.value;
    p.faults.corrupt = corrupt.value;
    p.faults.truncate = truncate.value;
    p.faults.seed = static_cast<std::uint64_t>(fault_seed.value);
    p.restart_at = restart.value;
    p.garbage = static_cast<int>(garbage.value);
    p.end_marker = !no_end.value;
    p.imu_accel_in_g = in_g.value;
    app.run(std::cout);
    return 0;
  });
}

}  // namespace freeinit::apps
