// Comparing simulated recordings bit for bit: a 64-bit FNV-1a digest of everything a recording
// holds (IMU samples, frames, points, labels, extrinsics, biases), and the first difference.
#pragma once

#include <freeinit/sim/simulator.h>

#include <cstdint>
#include <cstring>
#include <string>

namespace freeinit::sim::test {

class Fnv1a {
 public:
  void bytes(const void* p, std::size_t n) {
    const auto* b = static_cast<const unsigned char*>(p);
    for (std::size_t i = 0; i < n; ++i) {
      h_ ^= b[i];
      h_ *= 1099511628211ull;
    }
  }
  void add(double x) { bytes(&x, sizeof x); }
  void add(float x) { bytes(&x, sizeof x); }
  void add(const Vec3& v) {
    add(v.x());
    add(v.y());
    add(v.z());
  }
  std::uint64_t value() const { return h_; }

 private:
  std::uint64_t h_ = 1469598103934665603ull;
};

/// Digest of the recording's data (not of its config): equal digests mean equal recordings.
inline std::uint64_t recordingDigest(const Recording& r) {
  Fnv1a h;
  for (const ImuSample& s : r.imu) {
    h.add(s.t);
    h.add(s.gyro);
    h.add(s.accel);
  }
  for (std::size_t f = 0; f < r.frames.size(); ++f) {
    const LidarFrame& fr = r.frames[f];
    h.add(fr.stamp);
    for (std::size_t i = 0; i < fr.points.size(); ++i) {
      const DopplerPoint& p = fr.points[i];
      h.add(p.p_l.x());
      h.add(p.p_l.y());
      h.add(p.p_l.z());
      h.add(p.doppler);
      h.add(p.time_offset);
      h.add(p.intensity);
      const std::uint16_t line = p.line;
      h.bytes(&line, sizeof line);
      const auto label = static_cast<std::uint8_t>(r.labels[f][i]);
      h.bytes(&label, sizeof label);
    }
  }
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) h.add(r.extrinsics.R_bl(i, j));
  h.add(r.extrinsics.p_bl);
  h.add(r.b_g);
  h.add(r.b_a);
  return h.value();
}

/// "" when a and b hold the same samples, points, labels, calibration and biases bit for bit,
/// else where they first differ.
inline std::string firstDifference(const Recording& a, const Recording& b) {
  if (a.imu.size() != b.imu.size()) return "IMU sample count";
  for (std::size_t k = 0; k < a.imu.size(); ++k) {
    if (a.imu[k].t != b.imu[k].t || a.imu[k].gyro != b.imu[k].gyro ||
        a.imu[k].accel != b.imu[k].accel)
      return "IMU sample " + std::to_string(k);
  }
  if (a.frames.size() != b.frames.size()) return "frame count";
  for (std::size_t f = 0; f < a.frames.size(); ++f) {
    const auto &fa = a.frames[f], &fb = b.frames[f];
    if (fa.stamp != fb.stamp || fa.points.size() != fb.points.size() || a.labels[f] != b.labels[f])
      return "frame " + std::to_string(f);
    for (std::size_t i = 0; i < fa.points.size(); ++i) {
      const DopplerPoint &p = fa.points[i], &q = fb.points[i];
      if (p.p_l != q.p_l || p.doppler != q.doppler || p.time_offset != q.time_offset ||
          p.intensity != q.intensity || p.line != q.line)
        return "frame " + std::to_string(f) + " point " + std::to_string(i);
    }
  }
  if (a.extrinsics.R_bl != b.extrinsics.R_bl || a.extrinsics.p_bl != b.extrinsics.p_bl)
    return "true extrinsics";
  if (a.declared_extrinsics.R_bl != b.declared_extrinsics.R_bl ||
      a.declared_extrinsics.p_bl != b.declared_extrinsics.p_bl)
    return "declared extrinsics";
  if (a.lidar_time_offset != b.lidar_time_offset) return "LiDAR time offset";
  if (a.b_g != b.b_g || a.b_a != b.b_a) return "biases";
  return "";
}

}  // namespace freeinit::sim::test
