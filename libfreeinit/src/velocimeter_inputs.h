// What feeds a velocimeter run over an IMU + LiDAR stream (which points it uses, the gyro sample
// and the aided acceleration at each IMU step), shared by the initialization passes
// (paper_pipeline.cpp, joint_pipeline.cpp) and the Doppler-inertial odometry that continues after
// them.
#pragma once

#include <freeinit/config.h>
#include <freeinit/types.h>
#include <freeinit/velocimeter.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace freeinit::detail {

/// A point the velocimeter can use: finite, with a range inside [min_range, max_range].
inline bool usablePoint(const DopplerPoint& p, const VelocimeterParams& vp) {
  if (!p.p_l.allFinite() || !std::isfinite(p.doppler) || !std::isfinite(p.time_offset))
    return false;
  const double r = p.p_l.norm();
  return r > 0 && r >= vp.min_range && r <= vp.max_range;
}

/// The point stride that brings the point rate of the first frame with a measurable span closest
/// to max_point_rate (1 when no frame tells the rate). `Frames`: a sequence of items with a
/// `points` vector.
template <class Frames>
int automaticPointStride(const Frames& frames, double max_point_rate) {
  for (const auto& f : frames) {
    if (f.points.size() < 2) continue;
    const double span = f.points.back().time_offset - f.points.front().time_offset;
    if (!(span > 0)) continue;
    const double rate = static_cast<double>(f.points.size()) / span;
    return std::max(1, static_cast<int>(std::lround(rate / max_point_rate)));
  }
  return 1;
}

/// Gyro update with IMU sample k and its slope to sample k + 1 (none at the last sample).
inline void updateGyroAt(Velocimeter& velocimeter, const std::vector<ImuSample>& imu,
                         std::size_t k) {
  const bool has_next = k + 1 < imu.size();
  velocimeter.updateGyro(imu[k].gyro, has_next ? imu[k + 1].gyro : imu[k].gyro,
                         has_next ? imu[k + 1].t - imu[k].t : 0.0);
}

/// Accelerometer-aided propagation from IMU sample k: the body acceleration
/// a_b = f - b_a + g_b (g_b: gravity in the body frame at sample k) and its slope to sample
/// k + 1, gravity in b turning as dg_b/dt = -omega x g_b.
inline void setAidedAcceleration(Velocimeter& velocimeter, const std::vector<ImuSample>& imu,
                                 std::size_t k, const Vec3& b_a, const Vec3& g_b) {
  const Vec3 a_k = imu[k].accel - b_a + g_b;
  Vec3 slope = Vec3::Zero();
  if (k + 1 < imu.size()) {
    const double dt = imu[k + 1].t - imu[k].t;
    const Vec3 g_b_next = g_b - velocimeter.omega_b().cross(g_b) * dt;
    slope = (imu[k + 1].accel - b_a + g_b_next - a_k) / dt;
  }
  velocimeter.setAcceleration(a_k, slope);
}

}  // namespace freeinit::detail
