// Integration of a simulated IMU (true biases removed) from the true initial state, to compare
// with the ground truth: classical RK4 whose mid-step signals are interpolated from the samples.
#pragma once

#include <freeinit/sim/simulator.h>

#include <algorithm>
#include <vector>

namespace freeinit::sim::test {

inline Mat3 skew(const Vec3& w) {
  Mat3 S;
  S << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return S;
}

inline Mat3 orthonormalize(const Mat3& R) { return Quat(R).normalized().toRotationMatrix(); }

/// Bias-free IMU signal at the midpoint of samples k, k+1: cubic (4-point) interpolation, whose
/// error is O(h^4) instead of the O(h^2) of a linear one; linear at the ends.
template <typename Get>
Vec3 midpoint(const std::vector<ImuSample>& imu, std::size_t k, Get get) {
  if (k == 0 || k + 2 >= imu.size()) return 0.5 * (get(imu[k]) + get(imu[k + 1]));
  return (-get(imu[k - 1]) + 9.0 * get(imu[k]) + 9.0 * get(imu[k + 1]) - get(imu[k + 2])) / 16.0;
}

struct IntegrationError {
  double attitude = 0;  ///< [rad] max over samples
  double position = 0;  ///< [m]
  double velocity = 0;  ///< [m/s]
};

/// Classical RK4 on (R_wb, v_w, p_w) with Rdot = R [omega]x, vdot = R f + g, pdot = v, the
/// stage values at t + h/2 from the interpolated samples.
inline IntegrationError integrate(const Recording& rec, double horizon) {
  const Vec3 g_w = rec.g_w;
  auto gyro = [&](const ImuSample& s) -> Vec3 { return s.gyro - rec.b_g; };
  auto acc = [&](const ImuSample& s) -> Vec3 { return s.accel - rec.b_a; };
  const TruthState s0 = rec.truth(rec.imu.front().t);
  Mat3 R = s0.R_wb;
  Vec3 v = s0.v_w, p = s0.p_w;
  IntegrationError err;
  for (std::size_t k = 0; k + 1 < rec.imu.size(); ++k) {
    const double h = rec.imu[k + 1].t - rec.imu[k].t;
    if (rec.imu[k + 1].t - rec.imu.front().t > horizon + 1e-9) break;
    const Vec3 w0 = gyro(rec.imu[k]), w1 = gyro(rec.imu[k + 1]), wm = midpoint(rec.imu, k, gyro);
    const Vec3 f0 = acc(rec.imu[k]), f1 = acc(rec.imu[k + 1]), fm = midpoint(rec.imu, k, acc);
    const Mat3 kR1 = R * skew(w0);
    const Vec3 kv1 = R * f0 + g_w, kp1 = v;
    const Mat3 R2 = R + 0.5 * h * kR1;
    const Mat3 kR2 = R2 * skew(wm);
    const Vec3 kv2 = R2 * fm + g_w, kp2 = v + 0.5 * h * kv1;
    const Mat3 R3 = R + 0.5 * h * kR2;
    const Mat3 kR3 = R3 * skew(wm);
    const Vec3 kv3 = R3 * fm + g_w, kp3 = v + 0.5 * h * kv2;
    const Mat3 R4 = R + h * kR3;
    const Mat3 kR4 = R4 * skew(w1);
    const Vec3 kv4 = R4 * f1 + g_w, kp4 = v + h * kv3;
    R = orthonormalize(R + h / 6.0 * (kR1 + 2.0 * kR2 + 2.0 * kR3 + kR4));
    p += h / 6.0 * (kp1 + 2.0 * kp2 + 2.0 * kp3 + kp4);
    v += h / 6.0 * (kv1 + 2.0 * kv2 + 2.0 * kv3 + kv4);
    const TruthState s = rec.truth(rec.imu[k + 1].t);
    err.attitude = std::max(err.attitude, Eigen::AngleAxisd(s.R_wb.transpose() * R).angle());
    err.position = std::max(err.position, (s.p_w - p).norm());
    err.velocity = std::max(err.velocity, (s.v_w - v).norm());
  }
  return err;
}

}  // namespace freeinit::sim::test
