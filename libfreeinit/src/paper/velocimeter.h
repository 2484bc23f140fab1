// The Doppler-inertial velocimeter (DIV), paper Sec. III-B: a linear Kalman filter updated by every
// LiDAR point (scalar Doppler update) and every gyro sample.
//
// State x = [v_l (3), v_b (3), omega_b (3), b_g (3)]:
//   v_l      LiDAR velocity w.r.t. w, in l          [m/s]
//   v_b      body velocity w.r.t. w, in b           [m/s]
//   omega_b  body angular velocity, in b            [rad/s]
//   b_g      gyro bias, in b                        [rad/s]
// Observations (paper Eq. (doppler_vel_obs), (ang_vel_obs)):
//   Doppler, LiDAR model  z = -d_l^T v_l + n
//   Doppler, body model   z = -(R_bl d_l)^T (v_b + omega_b x p_bl) + n
//   gyro                  z = omega_b + b_g + n_g
// Propagation (paper Eq. (continuous_model)) with continuous-time process noise (Q dt per step,
// so the tracking bandwidth does not depend on how many points a scene returns). With
// `kinematic_propagation` the nominal velocities also follow the body-frame kinematics
// dv_b/dt = a_b - omega_b x v_b (and likewise v_l with omega_l = R_bl^T omega_b), and omega_b
// follows the slope of the gyro between its samples; the random walk then only has to absorb a_b.
//
// Implementation notes. The LiDAR-velocity block is driven by omega_b only as a known input, so
// its covariance never correlates with the body block: P is kept as two blocks, P_l (3x3) and
// P_b (9x9, [v_b omega_b b_g]). Each block is then a consistent filter using each Doppler value
// once; a consumer combining v_l and v_b (the gravity solver's two equations) must not treat them
// as independent. Covariance updates are symmetric rank-1 downdates, kept symmetric by
// construction; the covariance transition F P F^T is applied every 2 ms of accumulated time.
#pragma once

#include <freeinit/config.h>
#include <freeinit/types.h>

namespace freeinit {

/// What the velocimeter reads of the configuration ([doppler], [imu], [paper_velocimeter]; see
/// velocimeterParams()). Defaults: those of FreeInitConfig.
struct VelocimeterParams {
  double doppler_sigma = 0.03;     ///< [m/s] Doppler noise std
  double gyro_sigma = 0.002;       ///< [rad/s] gyro white noise per sample
  double vel_random_walk = 10.0;   ///< [m/s^2/sqrt(Hz)] v_l, v_b random walk density
  double omega_random_walk = 1.0;  ///< [rad/s^2/sqrt(Hz)] omega_b random walk density
  /// [m/s^2/sqrt(Hz)] v_l, v_b random walk density once accelerometer-aided (setAcceleration())
  double aided_vel_random_walk = 0.03;
  double gyro_bias_random_walk = 1e-4;  ///< [rad/s/sqrt(s)] Gauss-Markov driving noise
  double gyro_bias_tau = 1000.0;        ///< [s] Gauss-Markov correlation time
  double gyro_bias_sigma0 = 0.015;      ///< [rad/s] initial gyro bias std
  Vec3 gyro_bias_prior = Vec3::Zero();  ///< [rad/s] initial gyro bias
  bool kinematic_propagation = true;    ///< add -omega x v and the gyro slope to the propagation
  /// Let the Doppler update omega_b and b_g through the lever arm (PaperVelocimeterParams).
  bool doppler_updates_omega = false;
  // Gating of dynamic points and gross outliers, on the Doppler residual.
  double gate_sigma = 4.0;  ///< [-] reject |r| > gate_sigma * sqrt(S) ...
  double gate_min = 0.15;   ///< [m/s] ... but never below this
  double gate_rel = 0.01;   ///< [-] ... plus this fraction of the LiDAR speed
};

/// The velocimeter's settings from the configuration.
VelocimeterParams velocimeterParams(const FreeInitConfig& config);

class Velocimeter {
 public:
  using Mat9 = Eigen::Matrix<double, 9, 9>;

  Velocimeter(const VelocimeterParams& params, const Extrinsics& extrinsics);

  /// Starts the filter at time t [s] with a LiDAR velocity and its covariance (bootstrap), the
  /// first gyro sample, and the gyro bias prior from the parameters.
  void start(double t, const Vec3& v_l, const Mat3& cov_v_l, const Vec3& gyro);

  /// Propagates the state to time t (>= current time).
  void propagate(double t);

  /// Result of one Doppler update.
  struct DopplerOutcome {
    bool accepted = false;
    double residual = 0;  ///< [m/s] body-model innovation
  };
  /// Doppler update with one point (direction and range from p_l). Propagate to its time first.
  DopplerOutcome updateDoppler(const Eigen::Vector3f& p_l, double doppler);

  /// Gyro update with one sample; `next_gyro`/`dt_next` give the slope to the next sample
  /// (dt_next <= 0: no slope). Propagate to the sample time first.
  void updateGyro(const Vec3& gyro, const Vec3& next_gyro, double dt_next);

  /// Sets the angular acceleration the propagation uses until the next gyro update [rad/s^2].
  void setOmegaSlope(const Vec3& slope) { omega_slope_ = slope; }

  /// Accelerometer-aided propagation (refinement passes): from now on dv_b/dt = a_b(t) - omega x
  /// v_b with a_b(t) = a_b + a_b_slope (t - now), the body acceleration in b from the accelerometer
  /// once b_a and gravity are known, and the velocity random walk density becomes
  /// `aided_vel_random_walk`, which only has to absorb the errors of that acceleration.
  void setAcceleration(const Vec3& a_b, const Vec3& a_b_slope);

  /// Zero-velocity pseudo-measurements (v_l = v_b = omega_b = 0) with std `sigma`.
  void updateZeroVelocity(double sigma);

  /// Re-opens the velocity blocks after a zero-velocity phase, so motion is tracked at once.
  void releaseZeroVelocity(double sigma_v, double sigma_omega);

  double time() const { return t_; }
  const Vec3& v_l() const { return v_l_; }
  const Vec3& v_b() const { return v_b_; }
  const Vec3& omega_b() const { return omega_b_; }
  const Vec3& b_g() const { return b_g_; }
  const Mat3& covVl() const { return P_l_; }
  Mat3 covVb() const { return P_b_.block<3, 3>(0, 0); }
  Mat3 covBg() const { return P_b_.block<3, 3>(6, 6); }
  const Mat9& covBody() const { return P_b_; }

 private:
  void applyTransition();

  VelocimeterParams params_;
  Mat3 R_bl_;
  Vec3 p_bl_;
  double t_ = 0;
  Vec3 v_l_ = Vec3::Zero();
  Vec3 v_b_ = Vec3::Zero();
  Vec3 omega_b_ = Vec3::Zero();
  Vec3 b_g_ = Vec3::Zero();
  Vec3 omega_slope_ = Vec3::Zero();  ///< [rad/s^2] gyro slope used by the propagation
  bool aided_ = false;
  Vec3 a_b_ = Vec3::Zero();        ///< [m/s^2] body acceleration input (aided mode)
  Vec3 a_b_slope_ = Vec3::Zero();  ///< [m/s^3]
  double t_acc_ = 0;               ///< time of a_b_
  Mat3 P_l_ = Mat3::Identity();
  Mat9 P_b_ = Mat9::Identity();
  double pending_dt_ = 0;  ///< time since the covariance transition was last applied
  // Cached per-parameter constants.
  double q_v_ = 0, q_w_ = 0, q_b_ = 0, r_doppler_ = 0, r_gyro_ = 0;
  double gate_min2_ = 0, gate_k2_ = 0;
};

}  // namespace freeinit
