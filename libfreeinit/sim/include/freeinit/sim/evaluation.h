// The simulator's side of the evaluation (freeinit/eval): the truth of a recording as the
// evaluation's truth type, the errors and NEES of an initialization against it, and the
// Cramer-Rao bound of a window of that recording (its IMU samples, every static point's Doppler,
// its noise and true extrinsics, the estimator's priors).
#pragma once

#include <freeinit/config.h>
#include <freeinit/eval/cramer_rao_bound.h>
#include <freeinit/eval/state_errors.h>
#include <freeinit/eval/state_truth.h>
#include <freeinit/initial_state.h>
#include <freeinit/sim/simulator.h>

namespace freeinit::sim {

/// Errors and NEES of one state (eval::stateErrors and eval::stateNees in one record).
struct InitErrors {
  bool valid = false;                     ///< false when the result is not Ok
  double vel_b = 0;                       ///< [m/s] |v_b - v_b,true| at the state time
  double vel_b_true_norm = 0;             ///< [m/s] |v_b,true|
  double gravity_deg = 0;                 ///< [deg] angle between estimated and true gravity in b
  double gyro_bias = 0;                   ///< [rad/s] |b_g - b_g,true|
  double accel_bias = 0;                  ///< [m/s^2] |b_a - b_a,true|
  Vec3 accel_bias_vector = Vec3::Zero();  ///< [m/s^2] b_a - b_a,true (body frame)
  double accel_bias_vertical = 0;         ///< [m/s^2] component along gravity (observable at rest)
  /// Gravity error bound when the horizontal accelerometer bias is unobservable:
  /// atan(|b_a,true horizontal| / g) [deg].
  double gravity_deg_from_bias = 0;
  double nees_vel_b = 0;       ///< 3 dof
  double nees_tilt = 0;        ///< 2 dof
  double nees_gyro_bias = 0;   ///< 3 dof
  double nees_accel_bias = 0;  ///< 3 dof
};

/// The truth of `rec` at time t (biases and gravity of the recording).
eval::StateTruth stateTruth(const Recording& rec, double t);

/// Compares `state` with the truth of `rec` at state.timestamp.
InitErrors evaluate(const InitialState& state, const Recording& rec);

/// The gravity error [deg] an unobservable horizontal accelerometer bias implies (see
/// eval::gravityErrorFromBiasDeg).
double gravityErrorFromBiasDeg(const Vec3& b_a_true, const Vec3& g_b_true);

/// The bound model of `rec` for an estimator configured with `config`: the TRUE noise of the
/// simulated sensors (the Doppler sigma, the IMU's per-axis sigmas: gyroSigmaPerAxis(),
/// accelSigmaPerAxis()), the true extrinsics and gravity, constant biases (no random walk), and
/// the estimator's bias priors (gyro_bias_sigma0, accel_bias_prior_sigma). The noise `config`
/// declares does not enter: the bound is the physical limit whatever the estimator was told.
eval::BoundModel boundModel(const Recording& rec, const FreeInitConfig& config);

/// One figure per sensor's white noise.
struct NoiseFigures {
  double gyro = 0;     ///< [rad/s] per sample
  double accel = 0;    ///< [m/s^2] per sample
  double doppler = 0;  ///< [m/s] per point
};

/// The true noise of `rec` as one figure per sensor: the RMS over the axes of the IMU's per-axis
/// sigmas (what an estimator of one isotropic sigma converges to) and the Doppler sigma.
NoiseFigures trueNoise(const Recording& rec);

/// The bound at t_end over the IMU samples of `rec` in [t_begin, t_end], with the Doppler of every
/// point labelled Static in that span. ok = false (with a message) when fewer than 2 IMU samples
/// are in the span.
eval::Bound cramerRaoBound(const Recording& rec, const eval::BoundModel& model, double t_begin,
                           double t_end);

/// The bound of the window of `result`: result.trajectory.front().t .. result.state.timestamp.
/// ok = false when the result has no state or no trajectory.
eval::Bound cramerRaoBound(const Recording& rec, const FreeInitConfig& config,
                           const InitResult& result);

}  // namespace freeinit::sim
