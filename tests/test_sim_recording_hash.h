// A 64-bit FNV-1a digest of everything a simulated recording holds (IMU samples, frames, points,
// labels, extrinsics, biases), for tests that compare recordings bit for bit.
#pragma once

#include <freeinit/sim/simulator.h>

#include <cstdint>
#include <cstring>

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

}  // namespace freeinit::sim::test
