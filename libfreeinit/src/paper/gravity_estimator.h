// Accelerometer bias and gravity from the velocimeter's velocities and the integrated attitude
// (paper Sec. III-C, Eq. (acc_bias_gravity_opt)), solved with Ceres on the sphere S^2(9.81).
#pragma once

#include <freeinit/config.h>
#include <freeinit/types.h>

#include <string>
#include <vector>

namespace freeinit {

/// Parameters of GravityEstimator: [paper_gravity] and the accelerometer's model of [imu] (see
/// gravityParams()). Defaults: those of FreeInitConfig.
struct GravityParams {
  GravityFormulation formulation = GravityFormulation::Integrated;
  bool use_body_equation = true;        ///< residuals of the body kinematics
  bool use_lidar_equation = true;       ///< residuals of the LiDAR kinematics (lever arm terms)
  double accel_sigma = 0.02;            ///< [m/s^2] accelerometer white noise per sample
  double accel_bias_bound = 0.5;        ///< [m/s^2] |b_a| per axis is kept below this
  double accel_bias_prior_sigma = 0.1;  ///< [m/s^2] zero-mean prior
  double lowpass_cutoff_hz = 10.0;      ///< [Hz] for the differentiated formulation (<= 0: off)
  /// [s] correlation time of the velocity error (PaperGravityParams); 0: white errors.
  double velocity_error_correlation_time = 0.0;
  /// Each of the body and LiDAR equations gets half the information (PaperGravityParams).
  bool equations_share_errors = true;
  double loss_scale = 3.0;  ///< Cauchy loss scale on whitened residuals [sigma]
  int max_iterations = 50;
  /// Estimate a correction of the gyro bias with the integrated formulation (needs the gyro
  /// bias covariance, see estimate()).
  bool estimate_gyro_bias = true;
  /// Compute the covariance (`cov`, `cov_full`); off, they are left at their defaults.
  bool compute_covariance = true;
};

/// The solve's settings from the configuration (with the covariance).
GravityParams gravityParams(const FreeInitConfig& config);

/// The velocimeter's and integrator's estimates at one IMU sample of the window.
/// Frame w here is the first body frame of the window (not yet gravity-aligned).
struct KinematicSample {
  double t = 0;                     ///< [s] time since the window start
  Mat3 R_wb = Mat3::Identity();     ///< integrated attitude
  Vec3 v_b = Vec3::Zero();          ///< [m/s] body velocity in b
  Mat3 cov_v_b = Mat3::Identity();  ///< [(m/s)^2]
  Vec3 v_l = Vec3::Zero();          ///< [m/s] LiDAR velocity in l
  Mat3 cov_v_l = Mat3::Identity();  ///< [(m/s)^2]
  Vec3 omega_b = Vec3::Zero();      ///< [rad/s] bias-free angular velocity
  Vec3 accel = Vec3::Zero();        ///< [m/s^2] measured specific force (with bias)
};

/// Result of the accelerometer bias / gravity estimation.
struct GravityEstimate {
  bool ok = false;
  std::string message;               ///< reason when !ok, else the solver summary line
  Vec3 g_w = Vec3(0, 0, -kGravity);  ///< gravity in the first body frame, |g_w| = 9.81
  Vec3 b_a = Vec3::Zero();           ///< [m/s^2]
  /// Covariance of [g_w (3, rank 2: tangent to the sphere), b_a (3)], ambient coordinates.
  Eigen::Matrix<double, 6, 6> cov = Eigen::Matrix<double, 6, 6>::Identity();
  /// Correction of the gyro bias used to integrate R_wb (integrated formulation with a gyro-bias
  /// prior): b_g = b_g,used + delta_b_g, and the attitude becomes R_wb(t) = Exp(-M(t) delta_b_g)
  /// R_wb,used(t) with M(t) = int_0^t R_wb,used dt (left, world-frame perturbation).
  Vec3 delta_b_g = Vec3::Zero();
  /// Covariance of [g_w, b_a, delta_b_g] (9x9, ambient coordinates); its top-left 6x6 is `cov`.
  Eigen::Matrix<double, 9, 9> cov_full = Eigen::Matrix<double, 9, 9>::Identity();
  double final_cost = 0;
  int iterations = 0;
};

/// Solves for b_a and g_w given the window's kinematic samples.
class GravityEstimator {
 public:
  using Formulation = GravityFormulation;

  GravityEstimator() = default;
  explicit GravityEstimator(const GravityParams& p) : params_(p) {}
  const GravityParams& params() const { return params_; }

  /// Solves the problem. Requires >= 10 samples, sorted by time.
  /// `gyro_bias_cov`, when positive definite, is the covariance [(rad/s)^2] of the gyro bias used
  /// to integrate R_wb; the integrated formulation then also estimates its correction, which a
  /// rotating platform makes observable (a zero matrix: the attitude is taken as exact).
  /// `start`, if given and ok, is an earlier estimate in the same world frame (e.g. of a seed
  /// pass over the same window start): the solve starts from its g_w and b_a.
  GravityEstimate estimate(const std::vector<KinematicSample>& samples,
                           const Extrinsics& extrinsics, const Mat3& gyro_bias_cov = Mat3::Zero(),
                           const GravityEstimate* start = nullptr) const;

 private:
  GravityParams params_;
};

}  // namespace freeinit
