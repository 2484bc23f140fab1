// The joint window estimator: a Doppler-aided inertial filter and smoother over the window.
//
// Where the paper's pipeline runs a velocimeter first and solves for gravity and the accelerometer
// bias afterwards, this estimator solves for everything at once, with the accelerometer in the
// propagation from the first instant.
//
// State at IMU sample k (a node), world frame w (gravity-aligned, z up; the caller fixes the yaw
// and origin at the window start): R_wb (attitude), p_w, v_w (body origin), b_g, b_a (constant
// over the window up to a random walk). Error state (15), the order of the output covariance:
//   [dtheta (right perturbation, R = R^ Exp(dtheta)), dp_w, dv_w, db_g, db_a].
// Propagation between nodes: strapdown integration of the gyro and the accelerometer (midpoint
// rotation with coning correction, trapezoidal velocity, exact position for a linear
// acceleration); the IMU white noises are the process noise (sigma^2 dt^2 per step for the
// per-sample noise sigma at the IMU rate), the biases may walk.
// Doppler: every point is one scalar measurement at its own time t_j,
//   z_j = -d_j^T v_l(t_j) + n_j,   v_l = R_bl^T (R_wb^T v_w + omega_b x p_bl),
// d_j the unit direction in the LiDAR frame. A point belongs to the node whose interval holds its
// time (tau_j = t_j - t_k in [-dt_prev/2, dt_next/2)). Within the interval the LiDAR velocity is a
// quadratic in the normalized time s = tau / h (h the longer half interval),
// q(s) = q0 + q1 s + q2 s^2, through its exact values (IMU integration from the node state) at
// three instants, so that the squared residuals of all the node's points are an exact quadratic
// form in Q = [q0; q1; q2] (9 values):
//   sum_j (z_j + d_j^T q(s_j))^2 = c + 2 b^T Q + Q^T A Q,
//   A = [S_{m+n}]_{m,n=0..2} with S_m = sum s^m d d^T (m = 0..4), b = [sum s^m z d]_{m=0..2},
//   c = sum z^2.
// The node's points are gated one by one against the prediction, then enter as one update with
// the Jacobian dQ/dx of the node state: points are touched once, and everything after that
// (updates, smoothing, re-linearization) works on the sums.
//
// After the forward pass, an iterated Kalman smoother (Gauss-Newton on the whole window's MAP
// problem: a Kalman filter and Rauch-Tung-Striebel smoother on the errors around the last smoothed
// trajectory, repeated) removes the linearization errors of the first pass, whose early nodes start
// from an uncertain tilt and velocity. The estimate and covariance at the last node are those of
// the last iteration's filter (at the last node the filter and the smoother agree).
#pragma once

#include <freeinit/types.h>

#include <array>
#include <vector>

namespace freeinit {

/// Configuration of the joint window estimator.
struct DopplerInertialFilterParams {
  double doppler_sigma = 0.03;           ///< [m/s] Doppler white noise
  double gyro_sigma = 0.002;             ///< [rad/s] gyro white noise per sample
  double accel_sigma = 0.02;             ///< [m/s^2] accelerometer white noise per sample
  double gyro_bias_random_walk = 1e-4;   ///< [rad/s/sqrt(s)]
  double accel_bias_random_walk = 1e-3;  ///< [m/s^2/sqrt(s)]
  // Gating of dynamic points and gross outliers on the Doppler residual against the prediction.
  double gate_sigma = 4.0;  ///< [-] reject |r| > gate_sigma * sqrt(S) ...
  double gate_min = 0.15;   ///< [m/s] ... but never below this
  double gate_rel = 0.01;   ///< [-] ... plus this fraction of the LiDAR speed
  int max_iterations = 6;  ///< Gauss-Newton iterations after the forward pass, at most
  /// The iterations stop when no node moves by more than this many tolerances, the tolerances
  /// being 1e-5 rad, 1e-4 m, 1e-4 m/s, 1e-6 rad/s, 1e-4 m/s^2 (far below what the data resolve).
  double convergence = 1.0;
};

/// The nominal state at one node.
struct FilterState {
  double t = 0;  ///< [s] time of the node (the caller's time base)
  Mat3 R_wb = Mat3::Identity();
  Vec3 p_w = Vec3::Zero();  ///< [m]
  Vec3 v_w = Vec3::Zero();  ///< [m/s]
  Vec3 b_g = Vec3::Zero();  ///< [rad/s]
  Vec3 b_a = Vec3::Zero();  ///< [m/s^2]
};

class DopplerInertialFilter {
 public:
  using Mat15 = Eigen::Matrix<double, 15, 15>;
  using Vec15 = Eigen::Matrix<double, 15, 1>;
  using Vec9 = Eigen::Matrix<double, 9, 1>;
  using Mat9x15 = Eigen::Matrix<double, 9, 15>;

  DopplerInertialFilter(const DopplerInertialFilterParams& params, const Extrinsics& extrinsics);

  /// Starts with node 0 at IMU sample `s0` (x0.t is set to s0.t) with the prior (x0, P0).
  /// `P_gate`, if given, is the covariance node 0's points are gated with (a prior that is wide
  /// on purpose, so as not to count the start decision's returns twice, would let moving objects
  /// through the first node's gate).
  void start(const ImuSample& s0, const FilterState& x0, const Mat15& P0,
             const Mat15* P_gate = nullptr);

  /// Predicts the next node at IMU sample `s` from the current one, which must have been updated.
  void predict(const ImuSample& s);

  /// Opens the current node for points: `next` is the IMU sample after it (nullptr for the last
  /// node of the window, which then takes points up to its own time only). Points with
  /// tau = t - t_node in [-intervalBefore(), intervalAfter()) belong to it.
  void beginNode(const ImuSample* next);
  double intervalBefore() const { return before_; }
  double intervalAfter() const { return after_; }

  struct PointOutcome {
    bool accepted = false;
    double residual = 0;                              ///< [m/s] against the prediction
    Eigen::Vector3f x_b = Eigen::Vector3f::Zero();    ///< [m] in the node's body frame
  };
  /// One Doppler return of the open node: tau [s] from the node time, position in the LiDAR
  /// frame (non-zero), Doppler [m/s]. Gated against the prediction; accepted points enter the
  /// node's sums.
  PointOutcome addPoint(double tau, const Eigen::Vector3f& p_l, double doppler);

  /// Applies the open node's sums (iterated update of the node).
  void update();
  /// Rest knowledge at the open node (the IMU shows rest): zero body velocity with std
  /// `velocity_sigma` [m/s] and zero rotation, the gyro sample then measuring the bias, with std
  /// `rate_sigma` [rad/s] (<= 0: that part is not used). Call after update().
  void updateRest(double velocity_sigma, double rate_sigma);

  /// Iterated smoothing over all nodes; call once, after the last node was updated. Returns the
  /// number of iterations run.
  int smooth();

  std::size_t nodes() const { return nodes_.size(); }
  /// Smoothed state of node k after smooth(); before, the filtered one.
  const FilterState& state(std::size_t k) const { return nodes_[k].xs; }
  /// Covariance of the last node's state (the filter's of the last pass).
  const Mat15& covariance() const { return nodes_.back().P; }
  std::size_t acceptedPoints(std::size_t k) const { return nodes_[k].sums.n; }
  /// Sum of squared residuals of the accepted points at the current estimate, and their count.
  double residualSumOfSquares() const;
  std::size_t acceptedPointsTotal() const;
  /// Weighted information the Doppler gave about v_l at node k (sum d d^T / sigma^2).
  Mat3 dopplerInformation(std::size_t k) const;

  // The models, exposed for tests.
  /// Nominal propagation of x from IMU sample a to b.
  static FilterState propagate(const FilterState& x, const ImuSample& a, const ImuSample& b);
  /// LiDAR velocity in l at tau from the node state x (node at `cur`; `prev`/`next` the IMU
  /// samples around it, used on their side of the node).
  /// With J: also its Jacobian with respect to the error state of x (3x15).
  Vec3 lidarVelocity(const FilterState& x, const ImuSample* prev, const ImuSample& cur,
                     const ImuSample* next, double tau,
                     Eigen::Matrix<double, 3, 15>* J = nullptr) const;
  static FilterState boxplus(const FilterState& x, const Vec15& dx);
  /// a [-] b: the error state dx with b [+] dx = a.
  static Vec15 boxminus(const FilterState& a, const FilterState& b);
  /// Transition Jacobian of propagate() at x (analytic, first order).
  static Mat15 transitionJacobian(const FilterState& x, const ImuSample& a, const ImuSample& b);
  /// The same by central differences (for tests).
  static Mat15 numericalTransitionJacobian(const FilterState& x, const ImuSample& a,
                                           const ImuSample& b);

 private:
  using Mat9 = Eigen::Matrix<double, 9, 9>;

  /// The Doppler sums of one node.
  struct DopplerSums {
    // Eigen matrices are not zeroed by value-initialization: the constructor does it.
    DopplerSums() {
      for (Mat3& m : S) m.setZero();
      for (Vec3& v : bz) v.setZero();
    }
    std::array<Mat3, 5> S;   ///< sum s^m d d^T
    std::array<Vec3, 3> bz;  ///< sum s^m z d
    double c = 0;            ///< sum z^2
    std::size_t n = 0;
  };
  /// The node's sums as measurement rows: A = U D U^T restricted to D > 0, W = D^(1/2) U^T / sigma
  /// (rows x 9) and y0 = D^(-1/2) U^T b / sigma, so that the cost is |W Q + y0|^2 + const.
  struct Rows {
    Eigen::Matrix<double, Eigen::Dynamic, 9, 0, 9, 9> W;  // at most 9 rows, no heap
    Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 9, 1> y0;
  };

  struct Node {
    FilterState x;       ///< filtered
    FilterState xs;      ///< smoothed
    FilterState x_pred;  ///< predicted (first pass)
    Mat15 P = Mat15::Identity();
    ImuSample imu;                   ///< the node's IMU sample
    ImuSample imu_prev, imu_next;
    bool has_prev = false, has_next = false;
    double h = 0;                    ///< [s] time normalization of the interval
    std::array<double, 3> s_fit{};   ///< normalized instants of the q fit
    Mat3 V_inv = Mat3::Identity();   ///< inverse Vandermonde matrix of s_fit
    DopplerSums sums;
    Rows rows;
    double rest_velocity_sigma = 0;  ///< > 0: zero body velocity at the node
    double rest_rate_sigma = 0;      ///< > 0: the node's gyro sample measures the bias
  };

  /// Q = [q0; q1; q2] of node n at state x, optionally with its Jacobian dQ/ddx (9x15).
  Vec9 velocityPolynomial(const Node& n, const FilterState& x, Mat9x15* G) const;
  Mat15 processNoise(double dt) const;
  void buildRows(Node& n) const;
  /// Kalman update of the error dx (prior mean dx_prior relative to x_lin, covariance P) with
  /// node n's rows linearized at x_lin. Returns the posterior error relative to x_lin.
  Vec15 dopplerUpdate(const Node& n, const FilterState& x_lin, const Vec15& dx_prior,
                      Mat15& P) const;
  /// Rest update of the error dx (relative to x_lin, covariance P) at node n.
  static Vec15 restUpdate(const Node& n, const FilterState& x_lin, const Vec15& dx, Mat15& P);

  DopplerInertialFilterParams params_;
  Mat3 R_bl_;
  Vec3 p_bl_;
  std::vector<Node> nodes_;
  FilterState x0_prior_;
  Mat15 P0_ = Mat15::Identity();
  Mat15 P_gate0_ = Mat15::Identity();
  // The open node's prediction for gating.
  Vec9 q_open_ = Vec9::Zero();
  Mat3 M_open_ = Mat3::Zero();  ///< covariance of q0 (v_l at the node) from the prediction
  double before_ = 0, after_ = 0;
  double gate_min2_ = 0, gate_k2_ = 0, r_doppler_ = 0;
};

}  // namespace freeinit
