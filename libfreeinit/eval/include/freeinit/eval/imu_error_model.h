// The linearized error-state model of an IMU-driven body seen by a Doppler LiDAR, around a known
// true trajectory: the pieces the Cramer-Rao bound is assembled from, exposed for their tests.
//
// Model. The IMU samples are the inputs: omega = gyro - b_g - n_g, f = accel - b_a - n_a, with
//   dR_wb/dt = R_wb [omega]x,   dv_w/dt = R_wb f + g_w,   b_g, b_a constant (between nodes),
// and within IMU interval k the white noises n_g, n_a are those of sample k (constant over the
// interval, per-sample standard deviations gyro_sigma, accel_sigma). The Doppler of a static
// point of unit direction d_l (LiDAR frame) at time t is
//   y = -d_l^T R_bl^T (v_b + omega x p_bl) + noise,   v_b = R_wb^T v_w
// with the true extrinsics R_bl, p_bl (the Doppler sign: docs/architecture.md, "Frames, signs and
// the output contract").
//
// Error state (right attitude perturbation, as InitialState): R = R_true Exp(dtheta),
// v_w = v_w,true + dv, b = b_true + db, so x = [dtheta, dv, db_g, db_a] (12) and over an interval
// z = [x; n_g; n_a] (18). Linearized about the truth:
//   d(dtheta)/dt = -[omega]x dtheta - db_g - n_g
//   d(dv)/dt     = -R_wb [f_b]x dtheta - R_wb (db_a + n_a),   f_b = R_wb^T (a_w - g_w)
//   dy           = -d_l^T R_bl^T C z,  C = [[v_b]x, R_wb^T, [p_bl]x, 0, [p_bl]x, 0]
#pragma once

#include <freeinit/types.h>

namespace freeinit::eval {

/// The true kinematic state of the body at one instant, in a world frame with gravity g_w.
struct KinematicTruth {
  double t = 0;                  ///< [s]
  Mat3 R_wb = Mat3::Identity();  ///< attitude
  Vec3 v_w = Vec3::Zero();       ///< [m/s] velocity
  Vec3 a_w = Vec3::Zero();       ///< [m/s^2] acceleration
  Vec3 omega_b = Vec3::Zero();   ///< [rad/s] angular velocity in b
};

/// Offsets of the blocks of z = [dtheta, dv_w, db_g, db_a, n_g, n_a].
enum ErrorBlock : int { kDTheta = 0, kDVel = 3, kDBg = 6, kDBa = 9, kNg = 12, kNa = 15 };
inline constexpr int kErrorDim = 12;     ///< x
inline constexpr int kIntervalDim = 18;  ///< z = [x; n_g; n_a]

using Mat12 = Eigen::Matrix<double, 12, 12>;
using Mat18 = Eigen::Matrix<double, 18, 18>;
using Mat12x18 = Eigen::Matrix<double, 12, 18>;
using Mat3x18 = Eigen::Matrix<double, 3, 18>;

/// dz/dt = A z at the truth `s` (rows of n_g, n_a are zero: the noise is constant).
Mat18 errorDynamics(const KinematicTruth& s, const Vec3& g_w);

/// x(t_b) = T z(t_a) over [a.t, b.t] (b.t > a.t), from the truth at both ends only:
///   dtheta_b = D^T dtheta_a - D^T I (db_g + n_g),                D = R_a^T R_b, I = int D(s) ds
///   dv_b = dv_a - [V]x R_a dtheta_a + F (db_g + n_g) - R_a I (db_a + n_a),
///   V = v_b - v_a - g_w h (exact: the integral of a_w - g_w),
///   F = [V]x R_a I - int [V(s)]x R(s) ds (by parts from int [a_w - g_w]x R_a I(s) ds).
/// The two integrals use the Hermite (corrected trapezoid) rule with the derivatives at both ends,
/// exact to O(h^5).
Mat12x18 errorTransition(const KinematicTruth& a, const KinematicTruth& b, const Vec3& g_w);

/// C = d(v_b + omega_b x p_bl)/dz at the truth `s` (body frame).
Mat3x18 lidarVelocityJacobian(const KinematicTruth& s, const Vec3& p_bl);

/// dC/dt along the truth (z held fixed), from v_b' = R^T a_w - omega x v_b and
/// (R^T)' = -[omega]x R^T.
Mat3x18 lidarVelocityJacobianRate(const KinematicTruth& s);

}  // namespace freeinit::eval
