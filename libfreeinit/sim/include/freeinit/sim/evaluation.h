// Errors of an initialization against the simulator's ground truth, in gauge-free terms (body-frame
// velocity, gravity direction in the body frame, biases), with their normalized estimation errors
// squared (NEES) from the reported covariance.
#pragma once

#include <freeinit/initial_state.h>
#include <freeinit/sim/simulator.h>

namespace freeinit::sim {

struct InitErrors {
  bool valid = false;           ///< false when the result is not Ok
  double vel_b = 0;             ///< [m/s] |v_b - v_b,true| at the state time
  double vel_b_true_norm = 0;   ///< [m/s] |v_b,true|
  double gravity_deg = 0;       ///< [deg] angle between estimated and true gravity in b
  double gyro_bias = 0;         ///< [rad/s] |b_g - b_g,true|
  double accel_bias = 0;        ///< [m/s^2] |b_a - b_a,true|
  Vec3 accel_bias_vector = Vec3::Zero();  ///< [m/s^2] b_a - b_a,true (body frame)
  double accel_bias_vertical = 0;  ///< [m/s^2] component along gravity (observable at rest)
  /// Gravity error bound when the horizontal accelerometer bias is unobservable:
  /// atan(|b_a,true horizontal| / g) [deg].
  double gravity_deg_from_bias = 0;
  double nees_vel_b = 0;        ///< 3 dof
  double nees_tilt = 0;         ///< 2 dof
  double nees_gyro_bias = 0;    ///< 3 dof
  double nees_accel_bias = 0;   ///< 3 dof
};

/// Compares `state` with the truth of `rec` at state.timestamp.
InitErrors evaluate(const InitialState& state, const Recording& rec);

/// The gravity error [deg] an unobservable horizontal accelerometer bias implies,
/// atan(|b_a,true horizontal| / g), "horizontal" meaning orthogonal to the true gravity in b.
double gravityErrorFromBiasDeg(const Vec3& b_a_true, const Vec3& g_b_true);

}  // namespace freeinit::sim
