#include <freeinit/mrpt/StreamApp.h>
#include <freeinit/mrpt/conversions.h>
#include <freeinit/mrpt/rawlog_reader.h>
#include <freeinit/mrpt/stream_conversions.h>
#include <freeinit/net/udp_socket.h>
#include <freeinit/sim/simulator.h>

#include <algorithm>
#include <chrono>
#include <ostream>
#include <stdexcept>
#include <thread>

namespace freeinit::mrpt_glue {
namespace {

// One message to send, at `send_ns` (stream time).
struct Item {
  std::int64_t send_ns = 0;
  bool is_frame = false;
  net::ImuMessage imu;
  net::FrameMessage frame;
};

std::int64_t frameEnd(const net::FrameMessage& f) {
  float last = 0;
  for (const auto& p : f.points) last = std::max(last, p.time_offset);
  return f.stamp_ns + static_cast<std::int64_t>(static_cast<double>(last) * 1e9);
}

std::vector<Item> fromRawlog(const StreamAppParams& p) {
  std::vector<Item> items;
  std::optional<mrpt::poses::CPose3D> imu_pose;
  for (const auto& r : readRawlog(p.rawlog)) {
    try {
      if (auto imu = std::dynamic_pointer_cast<mrpt::obs::CObservationIMU>(r.obs)) {
        if (!p.imu_label.empty() && imu->sensorLabel != p.imu_label) continue;
        if (!imu_pose) imu_pose = imu->sensorPose;
        Item it;
        it.imu = imuMessage(*imu);
        it.send_ns = it.imu.stamp_ns;
        items.push_back(std::move(it));
      } else if (auto pc = std::dynamic_pointer_cast<mrpt::obs::CObservationPointCloud>(r.obs)) {
        if (!p.lidar_label.empty() && pc->sensorLabel != p.lidar_label) continue;
        const mrpt::poses::CPose3D base = imu_pose ? *imu_pose : mrpt::poses::CPose3D();
        Item it;
        it.is_frame = true;
        it.frame = frameMessage(*pc, extrinsicsFromPose(pc->sensorPose - base));
        it.send_ns = frameEnd(it.frame);
        items.push_back(std::move(it));
      }
    } catch (const std::exception& e) {
      throw InputError(p.rawlog + ": record " + std::to_string(r.index) + ": " + e.what());
    }
  }
  return items;
}

// The simulated recording, through the same observations freeinit-sim writes (so that stamps
// are on MRPT's 100 ns clock as in a rawlog).
std::vector<Item> fromSimulator(const StreamAppParams& p) {
  sim::ScenarioConfig sc = sim::preset(p.preset, p.seed);
  if (p.duration > 0) sc.duration = p.duration;
  if (p.points_per_frame > 0) sc.points_per_frame = p.points_per_frame;
  const sim::Recording rec = sim::simulate(sc);
  std::vector<Item> items;
  for (const auto& s : rec.imu) {
    Item it;
    it.imu = imuMessage(*imuToObservation(s, "IMU"));
    it.send_ns = it.imu.stamp_ns;
    items.push_back(std::move(it));
  }
  for (const auto& f : rec.frames) {
    Item it;
    it.is_frame = true;
    it.frame = frameMessage(*frameToObservation(f, rec.extrinsics, "LIDAR"), rec.extrinsics);
    it.send_ns = frameEnd(it.frame);
    items.push_back(std::move(it));
  }
  return items;
}

}  // namespace

void StreamApp::run(std::ostream& log) {
  if (!(params.speed >= 0)) throw std::invalid_argument("speed must be >= 0");
  std::vector<Item> items = params.rawlog.empty() ? fromSimulator(params) : fromRawlog(params);
  if (items.empty()) throw std::invalid_argument("nothing to send");
  // Delivery order: by send time; IMU first on ties, file order otherwise.
  std::stable_sort(items.begin(), items.end(), [](const Item& a, const Item& b) {
    return a.send_ns != b.send_ns ? a.send_ns < b.send_ns : (!a.is_frame && b.is_frame);
  });
  const double span = 1e-9 * static_cast<double>(items.back().send_ns - items.front().send_ns);
  log << "Streaming " << (params.rawlog.empty() ? "preset " + params.preset : params.rawlog) << ": "
      << items.size() << " messages over " << span << " s to UDP " << params.address << ":"
      << params.port << " at "
      << (params.speed > 0 ? std::to_string(params.speed) + "x real time" : "full speed") << "\n";

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
  const std::int64_t first = items.front().send_ns;
  bool restarted = false, garbage_sent = false;
  imu_sent = frames_sent = 0;
  for (std::size_t i = 0; i < items.size(); ++i) {
    const Item& it = items[i];
    const double t_stream = 1e-9 * static_cast<double>(it.send_ns - first);
    if (params.speed > 0)
      std::this_thread::sleep_until(t0 +
                                    std::chrono::duration_cast<std::chrono::nanoseconds>(
                                        std::chrono::duration<double>(t_stream / params.speed)));
    if (!restarted && params.restart_at >= 0 && t_stream >= params.restart_at) {
      sender.restart();
      restarted = true;
      log << "Sender restarted at " << t_stream << " s (new session)\n";
    }
    if (!garbage_sent && params.garbage > 0 && 2 * i >= items.size()) {
      sender.sendGarbage(params.garbage);
      garbage_sent = true;
    }
    if (it.is_frame) {
      sender.sendFrame(it.frame);
      ++frames_sent;
    } else {
      sender.sendImu(it.imu);
      ++imu_sent;
    }
  }
  if (params.end_marker) sender.sendEndOfStream();
  sender.flush();
  stats = sender.stats();
  log << "Sent " << imu_sent << " IMU samples and " << frames_sent << " frames in "
      << stats.datagrams << " datagrams (" << stats.bytes / 1e6 << " MB) in "
      << std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() << " s\n";
  if (stats.dropped + stats.duplicated + stats.reordered + stats.corrupted + stats.garbage > 0)
    log << "Injected faults: " << stats.dropped << " dropped, " << stats.duplicated
        << " duplicated, " << stats.reordered << " reordered, " << stats.corrupted << " corrupted, "
        << stats.garbage << " garbage datagrams\n";
  if (stats.refused > 0)
    log << "Warning: " << stats.refused << " datagrams refused by the system (no listener?)\n";
}

}  // namespace freeinit::mrpt_glue
