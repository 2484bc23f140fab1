// What feeds a velocimeter run over an IMU + LiDAR stream at each IMU step (the gyro sample and
// the aided acceleration), shared by the paper's initialization passes (paper_pipeline.cpp) and
// the Doppler-inertial odometry that continues after them.
#pragma once

#include <freeinit/types.h>

#include <cstddef>
#include <vector>

#include "paper/velocimeter.h"
#include "usable_points.h"

namespace freeinit::detail {

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
