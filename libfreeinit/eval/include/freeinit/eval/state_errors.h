// Errors of an initial state against the truth at the state time, in gauge-free terms: the body
// velocity in the body frame, the gravity direction in the body frame and the biases (none of them
// depends on the choice of world frame), their normalized estimation errors squared (NEES) from
// the state's own covariance, and the displacement over the initialization window.
#pragma once

#include <freeinit/eval/state_truth.h>
#include <freeinit/initial_state.h>

namespace freeinit::eval {

/// Gauge-free errors of one state (estimate minus truth).
struct StateErrors {
  double t = 0;                           ///< [s] the state time
  Vec3 v_b_true = Vec3::Zero();           ///< [m/s] true body velocity in b
  double speed = 0;                       ///< [m/s] |v_b,true|
  Vec3 velocity_vector = Vec3::Zero();    ///< [m/s] v_b - v_b,true
  double velocity = 0;                    ///< [m/s] |v_b - v_b,true|
  double gravity_deg = 0;                 ///< [deg] angle between the estimated and true g_b
  Vec3 gyro_bias_vector = Vec3::Zero();   ///< [rad/s] b_g - b_g,true
  double gyro_bias = 0;                   ///< [rad/s]
  Vec3 accel_bias_vector = Vec3::Zero();  ///< [m/s^2] b_a - b_a,true (body frame)
  double accel_bias = 0;                  ///< [m/s^2]
  double accel_bias_vertical =
      0;  ///< [m/s^2] |component along the true gravity| (observable at rest)
  /// [deg] the gravity error an unobservable horizontal accelerometer bias implies,
  /// atan(|b_a,true horizontal| / g).
  double gravity_deg_from_bias = 0;
};

/// The errors of `s` against `truth` (taken at s.timestamp; truth.t is not checked).
StateErrors stateErrors(const InitialState& s, const StateTruth& truth);

/// The gravity error [deg] an unobservable horizontal accelerometer bias implies,
/// atan(|b_a,true horizontal| / g), "horizontal" meaning orthogonal to the true gravity in b.
double gravityErrorFromBiasDeg(const Vec3& b_a_true, const Vec3& g_b_true);

/// Error [m] of the displacement over the initialization window expressed in the body frame at
/// its start, R_wb(t0)^T (p_w(t1) - p_w(t0)), t0 the first pose of r.trajectory and t1 the state
/// time: free of the world-frame choice. NaN without a state or a trajectory.
double displacementError(const InitResult& r, const StateTruth& at_start, const StateTruth& at_end);

/// 99.9 % quantiles of the chi-square distribution: a NEES above them has a 0.1 % chance for a
/// consistent estimator.
inline constexpr double kChi2Quantile999Dof2 = 13.82;
inline constexpr double kChi2Quantile999Dof3 = 16.27;

/// NEES of each gauge-free block against the state's covariance: body velocity (3 dof), tilt
/// (gravity direction, 2 dof), gyro bias (3), accelerometer bias (3).
struct Nees {
  double velocity = 0;
  double tilt = 0;
  double gyro_bias = 0;
  double accel_bias = 0;
};

/// The NEES of `s` against `truth`, with the pseudo-inverse of each block's covariance (directions
/// with a variance below 1e-9 of the block's largest are left out).
Nees stateNees(const InitialState& s, const StateTruth& truth);

/// The state's own standard deviation of each gauge-free block, as the Cramer-Rao bound gives
/// it: the square root of the block's trace (body velocity [m/s], tilt [deg], b_g [rad/s], b_a
/// [m/s^2]); NaN for a block without variance.
struct OwnSigmas {
  double velocity = 0;
  double gravity_deg = 0;
  double gyro_bias = 0;
  double accel_bias = 0;
};
OwnSigmas ownSigmas(const InitialState& s);

/// The linear maps of the 18-dim error state of InitialState (order [dtheta p v b_g b_a g],
/// dtheta a right perturbation: R_true = R_wb Exp(dtheta)) to the gauge-free errors, at the
/// estimate: rows 0-2 the body velocity v_b,true - v_b, rows 3-4 the tilt B^T (g^_true x g^) in
/// the basis B = tiltBasis(g_b) of the plane orthogonal to the estimated gravity, rows 5-7 b_g,
/// rows 8-10 b_a.
Eigen::Matrix<double, 11, 18> gaugeFreeJacobian(const InitialState& s);

/// An orthonormal basis (3x2) of the plane orthogonal to g (g != 0).
Eigen::Matrix<double, 3, 2> tiltBasis(const Vec3& g);

}  // namespace freeinit::eval
