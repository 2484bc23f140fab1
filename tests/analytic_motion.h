// A small closed-form rigid-body motion for solver tests: attitude, angular velocity, velocity and
// acceleration are exact at any time, so IMU samples and velocities built from it are exactly
// consistent. World frame: gravity aligned, z up.
#pragma once

#include <freeinit/rotation.h>
#include <freeinit/types.h>

#include <cmath>

namespace freeinit::test {

struct MotionState {
  Mat3 R_wb = Mat3::Identity();
  Vec3 omega_b = Vec3::Zero();  ///< [rad/s]
  Vec3 p_w = Vec3::Zero();      ///< [m]
  Vec3 v_w = Vec3::Zero();      ///< [m/s]
  Vec3 a_w = Vec3::Zero();      ///< [m/s^2]
};

/// R_wb = Rz(yaw) Ry(pitch) Rx(roll) with sinusoidal angles (a handheld-like rotational start,
/// 3-4 rad/s), position sinusoids plus a constant drift. `scale` = 0 gives a platform at rest
/// (with the attitude at t = 0).
class AnalyticMotion {
 public:
  explicit AnalyticMotion(double scale = 1.0) : s_(scale) {}

  MotionState at(double t) const {
    // Euler angles and their rates.
    const double yaw = 0.3 + s_ * (3.0 * t + 0.5 * std::sin(5.0 * t));
    const double yaw_d = s_ * (3.0 + 2.5 * std::cos(5.0 * t));
    const double pitch = 0.2 + s_ * 0.4 * std::sin(4.0 * t + 0.3);
    const double pitch_d = s_ * 1.6 * std::cos(4.0 * t + 0.3);
    const double roll = -0.1 + s_ * 0.5 * std::sin(6.0 * t);
    const double roll_d = s_ * 3.0 * std::cos(6.0 * t);
    const Mat3 Rz = Eigen::AngleAxisd(yaw, Vec3::UnitZ()).toRotationMatrix();
    const Mat3 Ry = Eigen::AngleAxisd(pitch, Vec3::UnitY()).toRotationMatrix();
    const Mat3 Rx = Eigen::AngleAxisd(roll, Vec3::UnitX()).toRotationMatrix();
    MotionState m;
    m.R_wb = Rz * Ry * Rx;
    m.omega_b = Rx.transpose() * Ry.transpose() * Vec3(0, 0, yaw_d) +
                Rx.transpose() * Vec3(0, pitch_d, 0) + Vec3(roll_d, 0, 0);
    m.p_w = s_ * Vec3(0.5 * t + 0.2 * std::sin(7.0 * t), 0.15 * std::cos(5.0 * t + 1.0),
                      0.1 * std::sin(9.0 * t));
    m.v_w = s_ * Vec3(0.5 + 1.4 * std::cos(7.0 * t), -0.75 * std::sin(5.0 * t + 1.0),
                      0.9 * std::cos(9.0 * t));
    m.a_w = s_ * Vec3(-9.8 * std::sin(7.0 * t), -3.75 * std::cos(5.0 * t + 1.0),
                      -8.1 * std::sin(9.0 * t));
    return m;
  }

 private:
  double s_;
};

/// Extrinsics used by the tests: a rotated LiDAR with a lever arm of ~14 cm.
inline Extrinsics testExtrinsics() {
  Extrinsics e;
  e.R_bl = Exp(Vec3(0.1, -0.2, 0.3));
  e.p_bl = Vec3(0.1, -0.05, 0.08);
  return e;
}

}  // namespace freeinit::test
