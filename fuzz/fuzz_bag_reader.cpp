// Fuzz harness: a whole ROS1 bag file through the importer's reader (structure guard, librosbag,
// message checks, roscpp deserialization, cloud decoding, trigger matching, reordering). The
// configuration follows the topics the input names: "/trigger" -> a radar-like layout with
// trigger stamps, "/radar" -> the same with bag-time stamps, otherwise the release layout.
// Invariants of the output: stamps strictly increasing per stream, frames non-empty with finite
// points sorted by time, the summary's point count equal to the points passed on. Then the same
// bag as the apps read it straight in (ros1::Ros1Reader: the index checked on opening, each chunk
// when first read), over the second half of its time span and then whole: the same invariants.
#include <freeinit/ros1/bag_reader.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>

#include "harness.h"

namespace freeinit::fuzz {
namespace {

bool contains(const std::uint8_t* d, std::size_t n, const char* s) {
  const std::size_t k = std::strlen(s);
  return n >= k && std::search(d, d + n, s, s + k) != d + n;
}

ros1::BagImportConfig configFor(const std::uint8_t* d, std::size_t n) {
  ros1::BagImportConfig c;  // the release layout
  c.unit_check_samples = 5;
  if (contains(d, n, "/radar")) {
    c.imu_topic = "/imu";
    c.lidar_topic = "/radar";
    c.cloud.time.field.name.clear();
    c.cloud.time.frame_duration = 0.0185;
    c.cloud.line.name.clear();
    c.stamp_source = ros1::StampSource::kBagTime;
    if (contains(d, n, "/trigger")) {
      c.stamp_source = ros1::StampSource::kTrigger;
      c.trigger_topic = "/trigger";
    }
  }
  return c;
}

}  // namespace

std::string fuzzOne(const std::uint8_t* data, std::size_t size) {
  std::string error;
  const std::string path = writeInput("bag", ".bag", data, size, error);
  if (path.empty()) return error;
  double last_imu = -1, last_frame = -1;
  std::size_t imu = 0, frames = 0, points = 0;
  ros1::BagReadCallbacks cb;
  cb.imu = [&](const ImuSample& s) {
    if (!(s.t > last_imu)) broken("IMU stamps do not increase");
    if (!s.gyro.allFinite() || !s.accel.allFinite()) broken("non-finite IMU sample");
    last_imu = s.t;
    ++imu;
  };
  cb.frame = [&](LidarFrame&& f) {
    if (!(f.stamp > last_frame)) broken("frame stamps do not increase");
    if (f.points.empty()) broken("empty frame passed on");
    for (std::size_t i = 0; i < f.points.size(); ++i) {
      const DopplerPoint& p = f.points[i];
      if (!p.p_l.allFinite() || !std::isfinite(p.doppler) || !std::isfinite(p.time_offset))
        broken("non-finite point passed on");
      if (i > 0 && p.time_offset < f.points[i - 1].time_offset) broken("points not sorted by time");
    }
    last_frame = f.stamp;
    ++frames;
    points += f.points.size();
  };
  std::string outcome;
  const ros1::BagImportConfig config = configFor(data, size);
  try {
    const ros1::BagSummary s = ros1::readBag(path, config, cb);
    if (s.points != points) broken("summary point count differs from the points passed on");
    outcome = "ok: " + std::to_string(imu) + " IMU samples, " + std::to_string(frames) +
              " frames, " + std::to_string(points) + " points";
  } catch (const ros1::BagError& e) {
    outcome = "error: " + firstLine(e.what());
  } catch (const std::invalid_argument& e) {
    outcome = "error: " + firstLine(e.what());
  }
  // Straight in: a window, then all of it, each a fresh stream.
  std::string straight;
  try {
    ros1::Ros1Reader reader(path, config);
    reader.staticExtrinsics();
    std::int64_t first = 0, last = 0;
    for (const auto& c : reader.checked().index().chunks)
      for (const auto& [conn, span] : c.connections) {
        first = first == 0 ? static_cast<std::int64_t>(span.first)
                           : std::min(first, static_cast<std::int64_t>(span.first));
        last = std::max(last, static_cast<std::int64_t>(span.last));
      }
    for (const bool window : {true, false}) {
      last_imu = last_frame = -1;
      bags::ImportStream stream(config, cb);
      if (window)
        reader.start(first + (last - first) / 2, last);
      else
        reader.start();
      while (reader.step(stream)) {
      }
      stream.finish(path);
    }
    straight = "ok";
  } catch (const ros1::BagError& e) {
    straight = "error: " + firstLine(e.what());
  } catch (const std::invalid_argument& e) {
    straight = "error: " + firstLine(e.what());
  }
  std::remove(path.c_str());
  return outcome + "; straight in: " + straight;
}

}  // namespace freeinit::fuzz
