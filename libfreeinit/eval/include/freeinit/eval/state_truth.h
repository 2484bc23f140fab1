// The true state of the body at one instant, as a simulator or a truth file beside a recording
// gives it: the one truth type every evaluation uses (errors, NEES, displacement).
#pragma once

#include <freeinit/types.h>

#include <optional>
#include <vector>

namespace freeinit::eval {

/// True state at time t. World frame w of the truth: any gravity-aligned or not frame in which
/// g_w is gravity; only frame-independent quantities are compared with an estimate.
struct StateTruth {
  double t = 0;                      ///< [s] UNIX time
  Quat q_wb = Quat::Identity();      ///< attitude R_wb (rotates b-vectors into w)
  Vec3 p_w = Vec3::Zero();           ///< [m] body (IMU) origin in w
  Vec3 v_w = Vec3::Zero();           ///< [m/s] body velocity in w
  Vec3 omega_b = Vec3::Zero();       ///< [rad/s] body angular velocity in b
  Vec3 b_g = Vec3::Zero();           ///< [rad/s] gyro bias
  Vec3 b_a = Vec3::Zero();           ///< [m/s^2] accelerometer bias
  Vec3 g_w = Vec3(0, 0, -kGravity);  ///< [m/s^2] gravity in w

  Mat3 R_wb() const { return q_wb.toRotationMatrix(); }
  /// Body velocity in the body frame.
  Vec3 v_b() const { return q_wb.conjugate() * v_w; }
  /// Gravity in the body frame.
  Vec3 g_b() const { return q_wb.conjugate() * g_w; }
};

/// The truth at time t from samples sorted by time: linear interpolation of p, v, omega (slerp of
/// the attitude), biases and gravity of the earlier sample. nullopt outside [front.t, back.t]
/// (1 us tolerance) or when `samples` is empty.
std::optional<StateTruth> interpolateTruth(const std::vector<StateTruth>& samples, double t);

}  // namespace freeinit::eval
