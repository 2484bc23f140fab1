// The posterior Cramer-Rao bound of an initialization window: the smallest covariance any unbiased
// estimator can reach, with the given priors, for the body velocity, the gravity direction (2 dof),
// the gyro bias and the accelerometer bias, all in the body frame at the end of the window (the
// state time), from the IMU samples and the Doppler of the static points of that window.
//
// Model (imu_error_model.h for the equations): the error state x = [dtheta, dv_w, db_g, db_a] at
// every IMU sample (node) of the window, propagated by the IMU with its white noises as process
// noise (n_g, n_a per sample, constant over the interval they start) and, as an option, bias
// random walks; every static point's Doppler at its own time is a scalar measurement through the
// true extrinsics and the lever arm; priors on b_g and b_a (as the estimator's); no information on
// the initial velocity and tilt. The yaw of the world is not observable (gravity is the only
// absolute direction): every reported quantity is invariant to it, so the yaw is fixed by
// information along that null direction, which is the same as fixing the yaw at the window start.
//
// Cost. A point's row over its interval's z_k = [x_k; n_k] is -d_l^T R_bl^T G(s), s the point's
// fraction of the interval, G the cubic Hermite interpolation of C(t) T(t) between the interval's
// ends (value and time derivative at both: error O(h^4), 7e-8 relative at 4.5 rad/s and 200 Hz).
// Each point adds w s^m d_l d_l^T (m = 0..6) to its interval's moments, so the information of
// any number of points in an interval is one 18x18 product; a forward information recursion over
// the nodes (substitute x_k = Phi^-1 (x_k+1 - Gamma n_k), marginalize n_k) gives the information
// of the last node. 300,000 points: a few milliseconds.
#pragma once

#include <freeinit/eval/imu_error_model.h>

#include <array>
#include <cstddef>
#include <limits>
#include <string>
#include <vector>

namespace freeinit::eval {

/// A prior standard deviation meaning "no prior".
inline constexpr double kNoPrior = std::numeric_limits<double>::infinity();

/// Noise, priors and calibration of the bound. The noise is the sensors' TRUE noise (a bound with
/// the figures an estimator was handed would move with them): per axis, the IMU's white noise is
/// gyro_sigma * gyro_axis_scale(i) and accel_sigma * accel_axis_scale(i) per sample.
struct BoundModel {
  Extrinsics extrinsics;                     ///< the TRUE LiDAR pose in the body frame
  Vec3 g_w = Vec3(0, 0, -kGravity);          ///< [m/s^2] gravity in the truth's world frame
  double doppler_sigma = 0.03;               ///< [m/s] Doppler noise std (default per point)
  double gyro_sigma = 0.002;                 ///< [rad/s] gyro white noise per sample (0: exact)
  double accel_sigma = 0.02;                 ///< [m/s^2] accelerometer noise per sample (0: exact)
  Vec3 gyro_axis_scale = Vec3::Ones();       ///< [-] > 0: each gyro axis' sigma / gyro_sigma
  Vec3 accel_axis_scale = Vec3::Ones();      ///< [-] > 0: each accelerometer axis' / accel_sigma
  double gyro_bias_random_walk = 0;          ///< [rad/s/sqrt(s)] (0: constant bias)
  double accel_bias_random_walk = 0;         ///< [m/s^2/sqrt(s)] (0: constant bias)
  double gyro_bias_prior_sigma = kNoPrior;   ///< [rad/s] prior std of b_g at the window start
  double accel_bias_prior_sigma = kNoPrior;  ///< [m/s^2] prior std of b_a at the window start

  /// Throws std::invalid_argument naming the field if a value is out of range (sigmas >= 0,
  /// doppler_sigma > 0, axis scales > 0, prior sigmas > 0 or kNoPrior).
  void validate() const;

  /// [rad/s] The gyro's white noise per sample, per axis.
  Vec3 gyroSigmaPerAxis() const { return gyro_sigma * gyro_axis_scale; }
  /// [m/s^2] The accelerometer's white noise per sample, per axis.
  Vec3 accelSigmaPerAxis() const { return accel_sigma * accel_axis_scale; }
};

/// The bound at the state time. A block that the data and priors cannot determine has an
/// infinite bound (and infinite diagonal entries in `cov`).
struct Bound {
  bool ok = false;  ///< false: `message` says why no bound was computed
  std::string message;
  double t_begin = 0;            ///< [s] first node (window start)
  double t_end = 0;              ///< [s] last node (state time)
  std::size_t nodes = 0;         ///< IMU samples in the window
  std::size_t measurements = 0;  ///< Doppler measurements used
  /// Covariance of [v_b (3) [m/s], tilt (2) [rad], b_g (3) [rad/s], b_a (3) [m/s^2]]; the tilt is
  /// the attitude error orthogonal to gravity in the basis `tilt_basis` (eval::tiltBasis(g_b)).
  Eigen::Matrix<double, 11, 11> cov = Eigen::Matrix<double, 11, 11>::Zero();
  Eigen::Matrix<double, 3, 2> tilt_basis = Eigen::Matrix<double, 3, 2>::Zero();
  // sqrt of the trace of each block: what an efficient estimator's error norm is in RMS.
  double velocity = std::numeric_limits<double>::quiet_NaN();     ///< [m/s]
  double gravity_deg = std::numeric_limits<double>::quiet_NaN();  ///< [deg]
  double gyro_bias = std::numeric_limits<double>::quiet_NaN();    ///< [rad/s]
  double accel_bias = std::numeric_limits<double>::quiet_NaN();   ///< [m/s^2]
  /// Nodes (IMU samples) of the window at which the truth is at rest (zero velocity and rate).
  std::size_t rest_nodes = 0;
  /// [rad/s] The gyro-bias bound of an estimator that knows of that rest: zeroRateGyroBiasBound
  /// over the rest nodes, with the model's gyro noise and prior; NaN without rest. Only for a
  /// window at rest throughout is it the bound of the whole window (otherwise the moving part's
  /// information is left out of it; `gyro_bias` leaves out the knowledge of rest).
  double gyro_bias_zero_rate = std::numeric_limits<double>::quiet_NaN();
};

/// [rad/s] The gyro-bias bound given rest: sqrt of the trace of the b_g covariance when the body is
/// known not to rotate over `rest_samples` gyro samples of per-axis white noise `gyro_sigma`
/// [rad/s], with a prior of std `prior_sigma` [rad/s] (kNoPrior: none) on each axis.
///
/// Derivation. At rest omega = 0, so each sample is y_k = b_g + n_k, n_k ~ N(0, diag(sigma_i^2))
/// independent over k (imu_error_model.h); the Doppler adds nothing on b_g beyond that knowledge
/// (it sees v_b + omega x p_bl, both known to be zero). The Fisher information of axis i is
/// N / sigma_i^2 + 1 / sigma_0^2, the axes are independent, so
///   bound^2 = sum_i 1 / (N / sigma_i^2 + 1 / sigma_0^2)  ->  sigma sqrt(3 / N)
/// for equal sigmas and no prior. NaN when rest_samples is 0; 0 for an exact gyro.
double zeroRateGyroBiasBound(const Vec3& gyro_sigma, std::size_t rest_samples,
                             double prior_sigma = kNoPrior);

/// Builds the bound of one window: construct with the truth at the IMU samples of the window,
/// add the Doppler measurements (any order), compute().
class CramerRaoBound {
 public:
  /// `nodes`: the truth at the IMU sample times of the window, at least 2, strictly increasing in
  /// time. Throws std::invalid_argument on a bad model or nodes.
  CramerRaoBound(const BoundModel& model, std::vector<KinematicTruth> nodes);

  /// Adds the Doppler of one static point at time t, direction d_l (LiDAR frame, non-zero; its
  /// length does not matter), with the model's Doppler sigma or `sigma` [m/s]. Points outside
  /// [first node, last node] are ignored: returns false.
  bool addDoppler(double t, const Vec3& d_l) { return addDoppler(t, d_l, model_.doppler_sigma); }
  bool addDoppler(double t, const Vec3& d_l, double sigma);

  /// The bound at the last node.
  Bound compute() const;

  // The model's pieces (for tests).
  const BoundModel& model() const { return model_; }
  const std::vector<KinematicTruth>& nodes() const { return nodes_; }
  std::size_t intervals() const { return nodes_.size() - 1; }
  /// x_k+1 = T z_k over interval k (without the bias random walk, which is added at node k+1).
  const Mat12x18& transition(std::size_t k) const { return transitions_[k]; }
  /// d(Doppler)/dz_k of a point at time t (in interval k) of unit direction d_l.
  Eigen::Matrix<double, 1, 18> dopplerRow(std::size_t k, double t, const Vec3& d_l) const;
  /// The information of the Doppler measurements added to interval k, on z_k.
  Mat18 intervalInformation(std::size_t k) const;
  /// The prior information on x at the first node (bias priors only).
  Mat12 priorInformation() const;
  /// The map from x at the last node to [v_b, tilt, b_g, b_a] (the rows of Bound::cov).
  Eigen::Matrix<double, 11, 12> outputJacobian() const;
  /// The unobservable direction of x at node k (a rotation of the world about gravity), unit.
  Eigen::Matrix<double, 12, 1> yawDirection(std::size_t k) const;

 private:
  using Moments = std::array<double, 42>;  ///< sum w s^m d d^T, m = 0..6, 6 entries each
  std::size_t intervalOf(double t);

  BoundModel model_;
  std::vector<KinematicTruth> nodes_;
  std::vector<Mat12x18> transitions_;
  /// Per interval the rows [G(0); h G'(0); G(h); h G'(h)] premultiplied by R_bl^T (12x18).
  std::vector<Eigen::Matrix<double, 12, 18>> hermite_;
  std::vector<Moments> moments_;
  std::size_t measurements_ = 0;
  std::size_t cursor_ = 0;
};

}  // namespace freeinit::eval
