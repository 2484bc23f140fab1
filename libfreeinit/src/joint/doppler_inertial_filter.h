// The joint window estimator: a Doppler-aided inertial filter and smoother over the window.
//
// Where the paper's pipeline runs a velocimeter first and solves for gravity and the accelerometer
// bias afterwards, this estimator solves for everything at once, with the accelerometer in the
// propagation from the first instant.
//
// State at IMU sample k (a node; by default one per sample, or every m-th sample, see below),
// world frame w (gravity-aligned, z up; the caller fixes the yaw
// and origin at the window start): R_wb (attitude), p_w, v_w (body origin), b_g, b_a (constant
// over the window up to a random walk), and the correction of the declared LiDAR-IMU
// calibration: the rotation phi_bl (R_bl,true = R_bl Exp(phi_bl)) and the LiDAR clock's offset
// dt_l (a point's true time is its LiDAR time minus dt_l), both constant with a prior from the
// declared accuracy (zero: the calibration is taken as exact). Error state (19); its first 15
// are the order of the output covariance:
//   [dtheta (right perturbation, R = R^ Exp(dtheta)), dp_w, dv_w, db_g, db_a, ddt_l, dphi_bl].
// The clock offset comes first of the calibration: with the rotation declared exact, the filter
// works on the first 16 components only.
// Propagation between nodes: strapdown integration of the gyro and the accelerometer (midpoint
// rotation with coning correction, trapezoidal velocity, exact position for a linear
// acceleration); the IMU white noises are the process noise (sigma^2 dt^2 per step for the
// per-sample noise sigma at the IMU rate), the biases may walk.
// Nodes at a bounded rate: with a fast IMU the caller may put the nodes at every m-th sample
// (beginNode's `next`). Every sample between two nodes is still integrated, one step per sample
// interval (the last one partial where an integration ends between samples), the steps'
// Jacobians composed (their block form is closed under composition), and the process noise of
// each step carried to the interval's end through the steps after it, each with its own
// samples' noise. A node's interval of returns is then m times longer (at a 2 kHz IMU with nodes
// at 200 Hz its intervals are those of a 200 Hz IMU), and the gyro in its lever-arm term is the
// least-squares quadratic through the samples of its interval of returns at the IMU's clock and
// the one on either side (gyroFit), so that every sample's noise reaches the returns it covers as
// with a node per sample; nothing else in the model changes.
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
// The gyro in v_l is the measured one, so its white noise moves the LiDAR velocity of all a
// node's returns alike (R_bl^T (n_g x p_bl)): that noise is marginalized out of the node's
// quadratic form (marginalizeLeverNoise), as the Cramer-Rao bound models it; on a long lever arm
// with thousands of returns per IMU sample it outweighs their Doppler noise.
// The node's points are gated one by one against the prediction, then enter as one update with
// the Jacobian dQ/dx of the node state: points are touched once (or twice, when the second gate
// or the caller takes some back out of the sums), and everything after that
// (updates, smoothing, re-linearization) works on the sums.
//
// After the forward pass, an iterated Kalman smoother (Gauss-Newton on the whole window's MAP
// problem: a Kalman filter and Rauch-Tung-Striebel smoother on the errors around the last smoothed
// trajectory, repeated) removes the linearization errors of the first pass, whose early nodes start
// from an uncertain tilt and velocity. The estimate and covariance at the last node are those of
// the last iteration's filter (at the last node the filter and the smoother agree).
#pragma once

#include <freeinit/types.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <vector>

namespace freeinit {

/// Configuration of the joint window estimator.
struct DopplerInertialFilterParams {
  double doppler_sigma = 0.03;           ///< [m/s] Doppler white noise
  double gyro_sigma = 0.002;             ///< [rad/s] gyro white noise per sample
  double accel_sigma = 0.02;             ///< [m/s^2] accelerometer white noise per sample
  double gyro_bias_random_walk = 1e-4;   ///< [rad/s/sqrt(s)]
  double accel_bias_random_walk = 1e-3;  ///< [m/s^2/sqrt(s)]
  /// The gyro noise through the lever arm in each node's Doppler (marginalizeLeverNoise); false:
  /// the measured gyro taken as exact there.
  bool lever_arm_gyro_noise = true;
  // Gating of dynamic points and gross outliers on the Doppler residual against the prediction.
  double gate_sigma = 4.0;  ///< [-] reject |r| > gate_sigma * sqrt(S) ...
  double gate_min = 0.15;   ///< [m/s] ... but never below this
  double gate_rel = 0.01;   ///< [-] ... plus this fraction of the LiDAR speed
  /// Second gate of each node's points, against the updated node, at this many sigmas of the
  /// residual (no floor): what the first gate, against the prediction, let through from slow
  /// moving objects (0: no second gate).
  double regate_sigma = 3.0;
  /// Coherence test of the second gate: a point is dropped when the mean residual of the
  /// coherence_window returns around it in the scan (those that passed the gate) is more than
  /// coherence_sigma of that mean's std from zero: the returns of an object that moves slowly
  /// along the line of sight pass a gate on single residuals, and together they bend the
  /// velocity (0 or 1: no such test).
  int coherence_window = 16;
  double coherence_sigma = 4.0;
  int max_iterations = 6;  ///< Gauss-Newton iterations after the forward pass, at most
  /// The smoother's iterations stop when no node moves by more than this many tolerances, or
  /// when the steps shrink tenfold or more and the next one, at the rate of the last two, would
  /// be below (Gauss-Newton's convergence). The tolerances being 1e-4 rad, 1e-3 m, 1e-4 m/s,
  /// 1e-5 rad/s, 1e-3 m/s^2 (for the calibration 1e-4 rad and 1e-4 s): a twentieth or less of
  /// what the data resolve (the bounds of the randomized scenarios are >= 0.002 m/s, 0.05 deg,
  /// 5e-4 rad/s and 0.01 m/s^2). Three of them: the step after a stop is far smaller than the
  /// last (the convergence is quadratic); against one, the held-out seeds 15000001-200 moved by
  /// at most 0.006 of their bound (most not at all), the presets by 0.007, for one smoother
  /// iteration in eight fewer on dyna_05.
  double convergence = 3.0;
};

/// The nominal state at one node.
struct FilterState {
  double t = 0;  ///< [s] time of the node (the caller's time base)
  Mat3 R_wb = Mat3::Identity();
  Vec3 p_w = Vec3::Zero();     ///< [m]
  Vec3 v_w = Vec3::Zero();     ///< [m/s]
  Vec3 b_g = Vec3::Zero();     ///< [rad/s]
  Vec3 b_a = Vec3::Zero();     ///< [m/s^2]
  Vec3 phi_bl = Vec3::Zero();  ///< [rad] correction of the declared R_bl
  double dt_l = 0;             ///< [s] LiDAR clock minus IMU clock
};

class DopplerInertialFilter {
 public:
  static constexpr int kStateDim = 19;
  /// The components before the calibration's (attitude, position, velocity, biases).
  static constexpr int kCoreDim = 15;
  /// Those and the clock offset (the components updated when only the offset is estimated).
  static constexpr int kTimeDim = 16;
  /// Index of each block in the error state.
  enum Block : int { kTheta = 0, kPos = 3, kVel = 6, kBg = 9, kBa = 12, kTime = 15, kRot = 16 };
  using MatS = Eigen::Matrix<double, kStateDim, kStateDim>;
  using VecS = Eigen::Matrix<double, kStateDim, 1>;
  using Vec9 = Eigen::Matrix<double, 9, 1>;
  using Mat9xS = Eigen::Matrix<double, 9, kStateDim>;

  DopplerInertialFilter(const DopplerInertialFilterParams& params, const Extrinsics& extrinsics);

  /// Appends an IMU sample (times increasing). Node k is at sample k, the first one given; the
  /// integration between two samples interpolates the gyro and the accelerometer with a cubic
  /// through the samples around them, so the filter wants sample k + 2 before it predicts node
  /// k + 1 or takes the points of node k (with fewer it falls back to lower orders).
  /// gyro_var [(rad/s)^2], accel_var [(m/s^2)^2]: the variance per axis the sample's value adds
  /// to the white noise gyro_sigma^2, accel_sigma^2 (a sample interpolated in place of a fault
  /// or a gap, ImuScreen; 0: measured). A step's process noise takes the larger of its two
  /// samples'; the lever-arm noise each sample's.
  void addImu(const ImuSample& s, double gyro_var = 0.0, double accel_var = 0.0);

  /// The prior of the window's first node, in terms the filter re-expresses wherever node 0's
  /// estimate moves in the smoother's iterations: roll and pitch in the world (the yaw and the
  /// origin are the world's gauge, held), the body velocity (a tilt change alone keeps it), the
  /// biases and the calibration (0: exact).
  struct StartPrior {
    double tilt_sigma = 0.2;          ///< [rad] world roll and pitch
    Mat3 cov_v_b = Mat3::Identity();  ///< [(m/s)^2] body velocity
    /// Node 0's points are gated with cov_v_b times this (a prior that is wide on purpose, so as
    /// not to count the start decision's returns twice, would let moving objects through).
    double gate_velocity_scale = 1.0;
    double gyro_bias_sigma = 0.015;  ///< [rad/s] about x0.b_g
    double accel_bias_sigma = 0.1;   ///< [m/s^2] about x0.b_a
    double rotation_sigma = 0;       ///< [rad] calibration rotation, per axis
    double time_sigma = 0;           ///< [s] LiDAR clock offset
  };
  /// Starts with node 0 at the first IMU sample (x0.t is set to its time) with the prior mean x0.
  void start(const FilterState& x0, const StartPrior& prior);
  /// Room for n nodes, when the caller knows how many the window will have: a node is a few
  /// kilobytes, and growing the nodes by doubling copies them and touches new memory each time.
  void reserveNodes(std::size_t n) { nodes_.reserve(n); }
  /// The smoother's work space for n nodes made now (and its memory touched), so that no
  /// smoothing, the final one included, waits for new memory: for windows of usual length
  /// (up to 1,000 nodes; a node's part is 5.8 kB); a longer one's is made by the smoothing.
  void prepareSmoothing(std::size_t n);
  /// The prior covariance of node 0 expressed at state x (velocity block scaled by v_scale).
  MatS priorCovariance(const FilterState& x, double v_scale = 1.0) const;
  /// The start's prior as the mean of an error at x (what priorCovariance(x) is the covariance of).
  VecS priorMean(const FilterState& x) const;

  /// Predicts the next node from the current one, which must have been updated.
  void predict();

  /// Opens the current node for points; `last`: the last node of the window, which then takes
  /// points up to its own time only. Points with tau = t - t_node in [-intervalBefore(),
  /// intervalAfter()) belong to it. `next`: the IMU sample (index among those given) of the next
  /// node, after this node's (0: the next sample); predict() puts it there.
  void beginNode(bool last, std::size_t next = 0);
  double intervalBefore() const { return before_; }
  double intervalAfter() const { return after_; }

  /// The open node's returns as arrays of `count` (tau [s] from the node time, kept in float,
  /// the form normalizedTime() rounds it to; position in the LiDAR frame, non-zero; Doppler
  /// [m/s]), held by the caller until update() returns: the filter reads them there, without a
  /// copy. update() gates them against the prediction (all at once: the prediction does not
  /// change while the node is open) and the accepted ones enter the node's sums. Once per node
  /// (none: a node without returns).
  struct OpenArrays {
    std::size_t count = 0;
    const float *tau = nullptr, *x = nullptr, *y = nullptr, *z = nullptr, *doppler = nullptr;
  };
  void setReturns(const OpenArrays& returns);

  /// Applies the open node's sums (iterated update of the node), then gates the node's points
  /// again against the update (regate_sigma) and solves the node again with those that pass.
  void update();
  /// After update(): whether the i-th return given to the open node was used in the end, and its
  /// residual against the update (against the prediction if the first gate rejected it).
  bool pointAccepted(std::size_t i) const { return open_.accepted[i] != 0; }
  double pointResidual(std::size_t i) const {
    return static_cast<double>(static_cast<float>(open_.residual[i]));
  }
  /// Takes back an accepted point of node k, a node already updated (exactly as given to
  /// setReturns() while it was open: the same tau, position and Doppler), e.g. once the whole
  /// window shows it on a moving object. smooth() next: it rebuilds the node's rows, which nothing
  /// else may use until then.
  void removePoint(std::size_t k, double tau, const Eigen::Vector3f& p_l, double doppler);
  /// The normalized time of a point at tau [s] from node k's time, as update() and
  /// removePoint() compute it (tau rounded to float: the form in which the caller keeps it).
  double normalizedTime(std::size_t k, double tau) const {
    return static_cast<double>(static_cast<float>(tau)) * nodes_[k].inv_h;
  }
  /// Rest knowledge at the open node (the IMU shows rest): zero body velocity with std
  /// `velocity_sigma` [m/s] per IMU sample the node stands for (those after the previous node up
  /// to its own: over the root of their count) and zero rotation, the gyro then measuring the bias:
  /// the mean of the measured gyro samples after the previous node up to this one's (those the
  /// caller saw at rest), with std `rate_sigma` [rad/s] per sample over the root of their count (<=
  /// 0, or no measured sample: that part is not used; a sample interpolated by the IMU screen
  /// measures no rate). Call after update().
  void updateRest(double velocity_sigma, double rate_sigma);
  /// Takes back the rest knowledge of the nodes at or after time t (the motion began before it
  /// was detected): the smoother does not use it. The filtered states keep it. keep_rate: only
  /// the zero velocity is taken back, the gyro samples still measure the bias (the returns show
  /// a translation, the gyro no rotation).
  void cancelRestFrom(double t, bool keep_rate = false);

  /// The white noises from here on ([m/s] per return, [rad/s] and [m/s^2] per sample; <= 0:
  /// unchanged), e.g. as the window's data tell them: the next nodes' gates and updates use
  /// them, and the next smooth() re-solves the whole window with them (every node's rows are
  /// rebuilt; the zero-rate measurements at rest take the new gyro noise).
  void setNoise(double doppler_sigma, double gyro_sigma, double accel_sigma);
  const DopplerInertialFilterParams& params() const { return params_; }
  /// The sum of squared Doppler residuals of every updated node's kept returns against that
  /// node's update (before the second solve; the second gate cut them at regate_sigma of their
  /// std), and their count.
  struct ForwardResiduals {
    double rss = 0;
    std::size_t returns = 0;
  };
  ForwardResiduals forwardResiduals() const { return {forward_rss_, forward_returns_}; }

  /// Iterated smoothing over the nodes so far, after the last one was updated. Returns the number
  /// of iterations run. The filter may go on afterwards (predict()), from the smoothed last node:
  /// smoothing once while the window is received leaves the final smoothing little to do.
  /// `looseness` (>= 1) multiplies the threshold DopplerInertialFilterParams::convergence: an
  /// early smoothing is the final one's starting point, and the final one converges on its own.
  /// `ahead`: more nodes follow and will be smoothed again; the forward pass that the next
  /// smoothing's first iteration makes over these nodes is made now, at the smoothed states, and
  /// kept (that iteration then computes only the nodes added since, or changed: returns taken
  /// back, rest cancelled).
  int smooth(double looseness = 1.0, bool ahead = false);

  /// What the data say of the calibration: after smooth(), one more forward pass around the
  /// smoothed trajectory with the calibration's prior std set to these (rad, s). When that
  /// smoothing converged, around the linearization of its last iteration (its polynomials,
  /// Jacobians and transitions, kept), which lies within the convergence threshold of the
  /// smoothed states; otherwise around the smoothed states themselves.
  struct CalibrationTest {
    bool ok = false;
    VecS correction = VecS::Zero();  ///< at the last node, relative to the linearization
    MatS covariance = MatS::Identity();
    double mahalanobis2 = 0;  ///< of the calibration correction (4 dof)
  };
  CalibrationTest testCalibration(double rotation_sigma, double time_sigma) const;
  /// After smooth(.., ahead): testCalibration()'s pass over the nodes so far, made now around the
  /// states that smoothing left, and kept: testCalibration() with the same std then continues it
  /// over the nodes added since (unless one of these changed since, as smooth()'s kept pass).
  /// So the call that closes a window runs the test over its last nodes only.
  void testCalibrationAhead(double rotation_sigma, double time_sigma);

  std::size_t nodes() const { return nodes_.size(); }
  /// Node k's IMU sample (index among those given to addImu()).
  std::size_t nodeSample(std::size_t k) const { return nodes_[k].k; }
  /// The LiDAR velocity over node k's interval at its smoothed state (after smooth()), as the
  /// coefficients of 1, s and s^2 (s = normalizedTime(k, tau)): the Doppler of a static return
  /// in direction d there is -d . v_l.
  Vec9 lidarVelocityPolynomial(std::size_t k) const {
    return velocityPolynomial(nodes_[k], nodes_[k].xs, nullptr);
  }
  /// lidarVelocityPolynomial() of every node (node k's at k): what the readers of the smoothed
  /// states below take, computed once when several read them.
  std::vector<Vec9> lidarVelocityPolynomials() const;
  /// Smoothed state of node k after smooth(); before, the filtered one.
  const FilterState& state(std::size_t k) const { return nodes_[k].xs; }
  /// Covariance of the last node's state (the filter's of the last pass).
  const MatS& covariance() const { return nodes_.back().P; }
  /// Covariance of node k's state as the filter of the last pass left it (after smooth(): its
  /// last iteration's forward pass), i.e. given the data up to node k: at the last node,
  /// covariance(); before it, an upper bound of the smoothed covariance.
  const MatS& nodeCovariance(std::size_t k) const { return nodes_[k].P; }
  /// Sum of squared residuals of the accepted points at the current estimate, and their count.
  double residualSumOfSquares() const { return residualSumOfSquares(lidarVelocityPolynomials()); }
  /// The same with the nodes' polynomials given (lidarVelocityPolynomials()).
  double residualSumOfSquares(const std::vector<Vec9>& Q) const;
  /// Node k's part of it, with its polynomial Q (not clamped: rounding may leave it below zero).
  double nodeResidualSumOfSquares(std::size_t k, const Vec9& Q) const;
  std::size_t acceptedPointsTotal() const;
  /// Whether each node's returns agree with its smoothed LiDAR velocity as the noise model says
  /// (after smooth()): for every node with at least min_returns accepted returns and no rest
  /// knowledge (rest is a model of its own, approximate for a hand-held rig's tremor), g = sum r d
  /// over them (r a return's residual, d its direction) is weighed against its covariance under
  /// the model, sigma_d^2 S_0 + G C G^T (S_m = sum s^m d d^T, G = [S_0 S_1 S_2], C the
  /// covariance the gyro noise through the lever arm gives Q), and the squares are summed. With the
  /// model right the sum is at most chi-square with `dof` degrees of freedom (the smoothing absorbs
  /// a part); an error common to a node's returns that the model leaves out (vibration, time-stamp
  /// jitter, a gyro noisier than configured) makes it larger, while the overall RMS of the
  /// residuals does not see it.
  struct NodeResiduals {
    double chi2 = 0;
    int dof = 0;  ///< 3 per node tested
  };
  /// Q: the nodes' polynomials (lidarVelocityPolynomials()).
  NodeResiduals nodeResiduals(std::size_t min_returns, const std::vector<Vec9>& Q) const;

  // The models, exposed for tests. `imu` holds the samples, x is the state at sample k.
  /// Integrates x from sample k over a signed tau (within one interval of k): the gyro and the
  /// accelerometer interpolated by cubics through the samples around the span, the rotation and
  /// the velocity by Simpson's rule (exact for cubic rates), the position by the same rule on the
  /// double integral. J (if given): the Jacobian of the result's error state (rows: dtheta, dp, dv,
  /// then the biases and the calibration) with respect to x's.
  static FilterState integrate(const FilterState& x, const std::vector<ImuSample>& imu,
                               std::size_t k, double tau, MatS* J = nullptr);
  /// integrate() over any tau: one step per sample interval from sample k on (backwards for a
  /// negative tau), the last one partial, their Jacobians composed.
  static FilterState integrateAcross(const FilterState& x, const std::vector<ImuSample>& imu,
                                     std::size_t k, double tau, MatS* J = nullptr);
  /// integrateAcross() back from sample k by tau (< 0, to no earlier than sample k_before)
  /// the way a node at k with a node before it at k_before integrates: the whole intervals
  /// through the chain of preintegrations forward from k_before to k, made at x_before's biases
  /// (with false if those are too far from x's for it, the node's own chain backward).
  static FilterState integrateBackThrough(const FilterState& x, const std::vector<ImuSample>& imu,
                                          std::size_t k_before, std::size_t k, double tau,
                                          const FilterState& x_before, MatS* J = nullptr,
                                          bool* through = nullptr);
  /// Nominal propagation of x from sample k to sample k + 1; F (if given): its transition
  /// Jacobian (analytic, first order).
  static FilterState propagate(const FilterState& x, const std::vector<ImuSample>& imu,
                               std::size_t k, MatS* F = nullptr);
  /// LiDAR velocity in l at LiDAR time tau after sample k (true time tau - x.dt_l) from the
  /// state x at sample k, with the corrected extrinsics; with J its Jacobian (3x19).
  Vec3 lidarVelocity(const FilterState& x, const std::vector<ImuSample>& imu, std::size_t k,
                     double tau, Eigen::Matrix<double, 3, kStateDim>* J = nullptr) const;
  static FilterState boxplus(const FilterState& x, const VecS& dx);
  /// a [-] b: the error state dx with b [+] dx = a.
  static VecS boxminus(const FilterState& a, const FilterState& b);
  /// Transition Jacobian of propagate() at x (analytic, first order).
  static MatS transitionJacobian(const FilterState& x, const std::vector<ImuSample>& imu,
                                 std::size_t k);
  /// The same by central differences (for tests).
  static MatS numericalTransitionJacobian(const FilterState& x, const std::vector<ImuSample>& imu,
                                          std::size_t k);
  /// Gyro and accelerometer at time t by Lagrange interpolation through the (up to four)
  /// samples of `imu` around it (two on each side where they exist). hint: an index near t
  /// (found by bisection without); gyro_rate (if given): the interpolant's time derivative.
  static void interpolateImu(const std::vector<ImuSample>& imu, double t, Vec3& gyro, Vec3& accel,
                             std::size_t hint = static_cast<std::size_t>(-1),
                             Vec3* gyro_rate = nullptr);
  /// The sums over the IMU samples before one (element i: over samples 0 .. i - 1) that a line
  /// fit reads, times u = t - t_0 from the first sample's.
  struct RunningSums {
    double u = 0, uu = 0, aa = 0, gg = 0;  ///< sum u, u^2, |accel|^2, |gyro|^2
    Vec3 a = Vec3::Zero(), ua = Vec3::Zero(), g = Vec3::Zero(), ug = Vec3::Zero();
  };
  /// sums extended to the samples of imu (one element per sample, and the first, zero).
  static void extendRunningSums(const std::vector<ImuSample>& imu, std::vector<RunningSums>& sums);
  /// The motion's specific force and angular acceleration at time t, for the clock offset's
  /// column (lidarVelocity()): the value of a straight line fitted to the accelerometer samples
  /// within kMotionHalfSpan of t and the slope of one fitted to the gyro's, each over the widest
  /// of that span, its half and its quarter (these two with eight samples or more) where its
  /// residuals are the sensor's white noise (sigma per sample, 99.9 %); where none is (a motion
  /// brisker than a line over a quarter of the span) or fewer than three samples are, the
  /// interpolant's (interpolateImu()). Returns whether gyro_rate is a fitted line's.
  /// complete (if given): a sample after every span read had arrived (later ones change nothing).
  /// running (if given): the running sums of imu (addImu() keeps the filter's), from which each
  /// span's sums are two differences, whatever the IMU rate; without, they are summed.
  static bool motionAt(const std::vector<ImuSample>& imu, double t, std::size_t hint,
                       double gyro_sigma, double accel_sigma, Vec3& accel, Vec3& gyro_rate,
                       bool* complete = nullptr, const std::vector<RunningSums>* running = nullptr);
  /// [s] Half the span of motionAt()'s fit.
  static constexpr double kMotionHalfSpan = 0.025;
  /// The samples lo..hi (returned) interpolateImu() uses at t (hint: as there).
  static std::size_t interpolationSpan(const std::vector<ImuSample>& imu, double t,
                                       std::size_t hint, std::size_t& lo);
  /// The Lagrange weights w (and their time derivatives dw) of samples lo..hi at t.
  static void lagrangeWeights(const std::vector<ImuSample>& imu, double t, std::size_t lo,
                              std::size_t hi, double* w, double* dw);

 private:
  using Mat9 = Eigen::Matrix<double, 9, 9>;

  /// The Doppler sums of one node: for m = 0..4 the upper triangle of sum s^m d d^T (xx, xy, xz,
  /// yy, yz, zz: one column per m), sum s^m z d (m = 0..2), sum z^2. A point adds one outer
  /// product of its direction's products with its time's powers (30 + 9 + 1 values).
  struct DopplerSums {
    // Eigen matrices are not zeroed by value-initialization: the constructor does it.
    DopplerSums() {
      S.setZero();
      bz.setZero();
    }
    Eigen::Matrix<double, 6, 5> S;  ///< column m: upper triangle of sum s^m d d^T
    Mat3 bz;                        ///< column m: sum s^m z d
    double c = 0;                   ///< sum z^2
    std::size_t n = 0;
    /// sum s^m d d^T as a full 3x3 matrix.
    Mat3 moment(int m) const;
  };
  /// The node's sums as measurement rows: A = L L^T (Cholesky, when well conditioned), W = L^T /
  /// sigma and y0 = L^-1 b / sigma; otherwise A = U D U^T restricted to D > 0, W = D^(1/2) U^T /
  /// sigma (rows x 9) and y0 = D^(-1/2) U^T b / sigma, so that the cost is |W Q + y0|^2 + const.
  struct Rows {
    Eigen::Matrix<double, Eigen::Dynamic, 9, 0, 9, 9> W;  // at most 9 rows, no heap
    Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 9, 1> y0;
  };

  /// The IMU along one integration from a sample over tau (tau != 0): gyro and accelerometer
  /// interpolated at tau / 4, tau / 2 and tau; what integrate() reads.
  struct ImuAlong {
    double tau = std::numeric_limits<double>::quiet_NaN();  ///< [s] what it holds (NaN: nothing)
    std::size_t samples = 0;  ///< the IMU samples there were (with fewer, lower orders)
    /// Every interpolation had a sample after the span it read: later samples change nothing.
    bool complete = false;
    std::array<Vec3, 3> gyro, accel;
  };
  static void sampleImu(const std::vector<ImuSample>& imu, std::size_t k, double tau,
                        ImuAlong& along);
  /// motionAt()'s result at one time, kept: a fit instant's time moves only with its node's
  /// dt_ref, so the smoother's iterations fit the lines once.
  struct MotionCache {
    /// [s] The time it holds (NaN: nothing), and the noises it was fitted with.
    double t = std::numeric_limits<double>::quiet_NaN();
    double gyro_sigma = 0, accel_sigma = 0;
    std::size_t samples = 0;  ///< the IMU samples there were
    bool complete = false;    ///< a sample after every span read had arrived
    bool gyro_line = false;   ///< motionAt()'s result, and its accel and gyro_rate
    Vec3 accel = Vec3::Zero(), gyro_rate = Vec3::Zero();
  };
  /// cache, sampled again unless it holds tau from sample k with as many samples as there are
  /// (or with all those it reads, complete).
  static const ImuAlong& imuAlong(const std::vector<ImuSample>& imu, std::size_t k, double tau,
                                  ImuAlong& cache);

  /// The blocks of integrate()'s Jacobian that are not those of the identity: the rows of
  /// dtheta, dp and dv against dtheta, db_g and db_a (dp against dv is tau I; every other block
  /// is the identity's). Those who read a few rows (lidarVelocity) take them without the 19x19.
  struct IntegrationJacobian {
    Mat3 th_th = Mat3::Identity(), th_bg = Mat3::Zero();
    Mat3 v_th = Mat3::Zero(), v_bg = Mat3::Zero(), v_ba = Mat3::Zero();
    Mat3 p_th = Mat3::Zero(), p_bg = Mat3::Zero(), p_ba = Mat3::Zero();
    double tau = 0;
    MatS matrix() const;
    /// F dx and F^T y, with the blocks.
    VecS times(const VecS& dx) const;
    VecS transposeTimes(const VecS& y) const;
  };
  /// The integration over the whole sample intervals from sample `from` to sample `to` (either
  /// way) expressed in the start's body frame (a preintegration, as Forster et al.'s): from any
  /// state x with the biases b = b0 + db, R' = R dR Exp(J.th_bg db_g), v' = v + g tau + R (dv +
  /// J.v_bg db_g + J.v_ba db_a), p' = p + v tau + g tau^2 / 2 + R (dp + J.p_bg db_g + J.p_ba
  /// db_a): exact at the biases b0 it was made at, first order in their change. What a node's
  /// linearizations repeat then costs the same whatever the number of samples.
  struct Preintegration {
    std::size_t from = 0, to = 0;
    std::size_t samples = 0;                      ///< the IMU samples there were (0: nothing held)
    bool complete = false;                        ///< ... all it reads (as ImuAlong)
    Vec3 b_g = Vec3::Zero(), b_a = Vec3::Zero();  ///< b0
    Mat3 dR = Mat3::Identity();
    Vec3 dv = Vec3::Zero(), dp = Vec3::Zero();
    IntegrationJacobian J;  ///< of the integration from R = I, v = p = 0 at b0
    /// The attitude and velocity increments at x's biases (first order in their change).
    void at(const FilterState& x, Mat3& E, Vec3& dv_x) const;
    /// dR, dv and dp from the end y of the integration over tau from R = I, v = p = 0 (gravity,
    /// which every step adds in the world frame as g tau and g tau^2 / 2, taken out).
    void endAt(const FilterState& y, double tau);
  };
  /// The integration from a node's sample over tau (to a fit instant, or to the next sample) as
  /// an increment (a Preintegration with to = from), made at one set of biases and applied at
  /// the state's to first order, as a spanning interval's: a linearization then costs a few
  /// products, whatever the IMU's rate, instead of an integration with its Jacobian (increment()).
  struct Increment {
    /// The IMU along its last step; [s] its span (NaN: none).
    ImuAlong along;
    double tau = std::numeric_limits<double>::quiet_NaN();
    Preintegration pre;
    Vec3 gyro = Vec3::Zero();  ///< [rad/s] the IMU's gyro at its end (the last step's)
  };
  /// A fit instant's caches: the integration to it, the motion there.
  struct FitInstant {
    Increment increment;
    MotionCache motion;
  };
  /// The preintegrations from one sample to each sample after it (or before it), made at one set
  /// of biases: prefix[i] to from + i + 1 (from - i - 1). An integration whose end moves (a fit
  /// instant moved by the clock offset's estimate, by whole samples at a fast IMU) reads another
  /// prefix, or extends the chain by the steps it lacks, instead of making it again.
  struct PreintegrationChain {
    std::vector<Preintegration> prefix;
    /// Counts the changes of prefixes already made (remade or dropped; not those added): what
    /// was read from them holds while it stays.
    std::size_t changes = 0;
  };
  /// A node's chains, from its sample to those after it and to those before it: the first holds
  /// the integration to the fit instant after the node and, further, to the next node.
  struct PreintegrationChains {
    PreintegrationChain ahead, behind;
    /// The preintegration back to the fit instant's sample through the node before's chain
    /// (backwardThrough), kept while that chain's prefixes stay (back_changes: its changes
    /// then; back.to: the sample).
    Preintegration back;
    std::size_t back_changes = std::numeric_limits<std::size_t>::max();
  };
  /// The process noise (attitude, position, velocity) over an interval spanning several samples,
  /// each step's carried to the interval's end through the steps after it: per unit gyro and
  /// accelerometer white variance (g, a: the white noises setNoise() may change later), and the
  /// absolute part the synthetic samples add (extra, ImuScreen; zero while every sample is a
  /// measured one).
  struct IntervalNoise {
    Mat9 g = Mat9::Zero(), a = Mat9::Zero(), extra = Mat9::Zero();
    bool has_extra = false;
  };
  struct Node {
    FilterState x;       ///< filtered
    FilterState xs;      ///< smoothed
    FilterState x_pred;  ///< predicted (first pass)
    MatS P = MatS::Identity();
    std::size_t k = 0;              ///< the node's IMU sample (index in imu_)
    std::size_t k_prev = 0;         ///< the previous node's (k for the first node)
    std::size_t k_next = 1;         ///< the next node's (beginNode)
    bool last = false;              ///< the window's last node (no points after its time)
    double h = 0;                   ///< [s] time normalization of the interval
    double inv_h = 1;               ///< [1/s] its inverse
    std::array<double, 3> s_fit{};  ///< normalized instants of the q fit
    Mat3 V_inv = Mat3::Identity();  ///< inverse Vandermonde matrix of s_fit
    DopplerSums sums;
    Rows rows;
    double rest_velocity_sigma = 0;  ///< > 0: zero body velocity at the node
    double rest_rate_sigma = 0;      ///< > 0: the node's gyro samples measure the bias ...
    std::size_t rest_samples = 1;    ///< ... so many (rest_rate_sigma is per sample) ...
    Vec3 rest_gyro = Vec3::Zero();   ///< ... their mean
    /// Opened after a rest node, its own rest not yet decided (the forward update's).
    bool after_rest = false;
    /// The returns do not depend on the clock offset (lidarVelocity()).
    bool still() const { return rest_velocity_sigma > 0 || after_rest; }
    /// [s] The clock offset the node's returns are integrated with (lidarVelocity()):
    /// the prior's or the last smoothing's when the node was opened (beginNode()), then, at a
    /// smoothing's start, the node's offset there (the forward filter's at the first smoothing, the
    /// last smoothing's after) once that moved away from it (referOffsets()).
    double dt_ref = 0;
    bool rows_stale = false;  ///< the sums changed after the rows were built
    /// The integrations every linearization of the node repeats (to its three fit instants and,
    /// `step`, with a node per sample to the next node), as increments: they depend on the IMU,
    /// the clock offset and the biases' grid cell only, so the smoother's iterations make them
    /// once (a cache; the filter is not for concurrent use).
    mutable std::array<FitInstant, 3> fit_imu;
    mutable Increment step;  ///< to the next sample (a node per sample)
    /// Intervals across several samples (spansSamples()): the IMU along the steps from sample k
    /// to each sample after it up to k_next (ahead[i]: k + i to k + i + 1) and before it down to
    /// k_prev (behind[i]: k - i to k - i - 1), sampled as ImuAlong; fit_imu then holds the
    /// last, partial step of each fit instant's integration.
    mutable std::vector<ImuAlong> ahead, behind;
    /// ... and the preintegrations of the whole intervals of the fit instants' integrations and
    /// of the interval to the next node; empty for a node per sample. The integration back to
    /// the fit instant before the node reads the chain forward of the node before
    /// (backwardThrough); this node's chain back is made only when that one does not hold.
    mutable PreintegrationChains pre;
    /// Intervals across several samples: the process noise over the interval to the next node,
    /// carried through the steps at the state predict() integrated.
    IntervalNoise noise;
    /// ... and the gyro in the lever-arm term: [rad/s] the coefficients of 1, s, s^2 (s = tau /
    /// h, tau the returns' time from the node's) of the least-squares fit through the samples
    /// of its interval of returns and the one on either side (gyroFit).
    std::array<Vec3, 3> gyro_fit{};
    Mat3 gyro_fit_cov = Mat3::Zero();  ///< ... their covariance per unit gyro_sigma^2
    bool gyro_fit_complete = true;     ///< ... made with every sample it reads
    /// Whether an interval of the node spans more than one sample interval.
    bool spansSamples() const { return k_next > k + 1 || k > k_prev + 1; }
  };

  /// Adds a point to the sums (w = 1) or takes it out (w = -1).
  static void accumulate(DopplerSums& sums, double s, const Vec3& d, double z, double w = 1.0);

  /// The open node's returns, structure of arrays. As given: `in`, the caller's (setReturns);
  /// after update()'s gates, per return in the order given: the residual (against the
  /// prediction, then against the update for those the first gate accepted), whether it is used,
  /// and the second gate's residual, its variance and verdict. The arrays only grow (to what the
  /// largest node needed), so that no return is written twice; `given` and `used` count what is
  /// valid in them.
  struct OpenReturns {
    OpenArrays in;  ///< the caller's
    // The per-return results, all 8 bytes wide: the loops over them vectorize without
    // conversions.
    std::vector<double> residual, residual2, variance2;
    std::vector<double> inv_norm;  ///< 1 / |p_l|, the first gate's, for the second
    std::vector<std::int64_t> accepted, passed;
    // The coherence test's, over the returns the second gate passed, in order: their index
    // among the given ones, the prefix sums of their residuals and variances, the verdict.
    std::vector<std::uint32_t> index;
    std::vector<double> cum_r, cum_v;
    std::vector<std::int64_t> coherent;
    std::size_t given = 0;  ///< returns given to the node
    std::size_t used = 0;   ///< accepted by the first gate
    void clear() {
      given = used = 0;
      in = {};
    }
    /// Room for the results of n given returns.
    void reserve(std::size_t n);
  };
  /// The first gate of the open node's returns against the prediction, and the sums of those
  /// it accepts.
  void gateAndSum(Node& n);

  /// Q = [q0; q1; q2] of node n at state x, optionally with its Jacobian dQ/ddx (9x19).
  Vec9 velocityPolynomial(const Node& n, const FilterState& x, Mat9xS* G) const;
  /// Throws std::invalid_argument unless Q holds one polynomial per node.
  void checkPolynomials(const std::vector<Vec9>& Q) const;
  /// Node k's part of a forward pass around the states xs: the state, its velocity polynomial
  /// and Jacobian (if the node has rows), and the transition to the next node (if any).
  struct Linearization {
    FilterState x;
    Vec9 Q;
    Mat9xS G;
    IntegrationJacobian F;
    FilterState x_next;
  };
  void linearize(std::size_t k, Linearization& L) const;
  /// smooth()'s forward pass around the states xs from node `first` on, the nodes before it as
  /// the last pass left them (first > 0: that pass was made around the same states).
  void smootherForward(std::size_t first);
  /// J := later J (the composition of two integrations: the block form is closed under it).
  static void compose(const IntegrationJacobian& later, IntegrationJacobian& J);
  /// The preintegration from -> to, from the chain when it holds it (from `from`, that way, with
  /// as many samples as there are or all it reads, and biases within a small change of x's: the
  /// first order's error then far below the integration's), else made (the chain extended, or
  /// made again from `from` at x's biases).
  static const Preintegration& preintegrated(const std::vector<ImuSample>& imu, std::size_t from,
                                             std::size_t to, const FilterState& x,
                                             std::vector<ImuAlong>& ahead,
                                             std::vector<ImuAlong>& behind,
                                             PreintegrationChain& chain);
  /// Whether the chain holds preintegrations from sample `from` that way whose biases are close
  /// enough to x's over a span of `span` [s] (preintegrated()).
  static bool chainHolds(const PreintegrationChain& chain, std::size_t from, bool forward,
                         double span, const FilterState& x);
  /// The increment from sample k over tau for a state x: from the cache when it holds it (that
  /// span, with as many samples as there are or all it reads, at the biases it is made at for
  /// x), else made (makeIncrement()).
  static const Increment& increment(const FilterState& x, const std::vector<ImuSample>& imu,
                                    std::size_t k, double tau, Increment& cache,
                                    const Node* chain = nullptr,
                                    PreintegrationChains* pre = nullptr,
                                    const Node* before = nullptr);
  /// The increment from sample k over tau at x's biases into cache (chain: the node at sample k,
  /// across its samples with its caches, pre and before as integrateAcross()).
  static void makeIncrement(const FilterState& x, const std::vector<ImuSample>& imu, std::size_t k,
                            double tau, Increment& cache, const Node* chain = nullptr,
                            PreintegrationChains* pre = nullptr, const Node* before = nullptr);
  /// D: the preintegration from the next node's sample (before.k_next) back to sample j
  /// (before.k <= j < before.k_next), from the chain forward of the node before (its prefixes to
  /// both samples, the first turned back); false (D not set) unless that chain holds at x's
  /// biases (chainHolds), made at them if needed.
  static bool backwardThrough(const std::vector<ImuSample>& imu, const Node& before, std::size_t j,
                              const FilterState& x, Preintegration& D);
  /// backwardThrough() into pre.back (the node's chains), unless it holds the one to sample j
  /// already.
  static bool backwardThrough(const std::vector<ImuSample>& imu, const Node& before,
                              PreintegrationChains& pre, std::size_t j, const FilterState& x);
  /// The node before n in nodes_ (n one of them), if its interval ends at n's sample; else null.
  const Node* nodeBefore(const Node& n) const;
  /// x moved by a preintegration (the time set to its last sample's); J: the blocks.
  static FilterState applyPreintegration(const Preintegration& P, const std::vector<ImuSample>& imu,
                                         const FilterState& x, IntegrationJacobian* J);
  /// integrateAcross() with the IMU along its full steps cached in ahead and behind (grown as
  /// needed) and along its last partial one in partial; *last (if given): the IMU along the
  /// integration's last step (nullptr: tau = 0, no step).
  /// pre (if given): the whole intervals through a preintegration of its chains (the one that
  /// way); before (if given, with pre): the node before the one at sample k, whose chain forward
  /// then gives the whole intervals back towards it (backwardThrough).
  static FilterState integrateAcross(const FilterState& x, const std::vector<ImuSample>& imu,
                                     std::size_t k, double tau, IntegrationJacobian* J,
                                     std::vector<ImuAlong>& ahead, std::vector<ImuAlong>& behind,
                                     ImuAlong& partial, const ImuAlong** last,
                                     PreintegrationChains* pre = nullptr,
                                     const Node* before = nullptr);
  /// integrate() with the IMU along the span given (sampled over tau from sample k; not read
  /// at tau = 0).
  static FilterState integrate(const FilterState& x, const std::vector<ImuSample>& imu,
                               std::size_t k, double tau, IntegrationJacobian* J,
                               const ImuAlong& along);
  /// propagate() from node n to the next one (its IMU sampled once), with the transition's
  /// blocks (if F); noise (if given): the process noise over the interval (Node::noise), when it
  /// spans several samples.
  FilterState propagate(const Node& n, const FilterState& x, IntegrationJacobian* F,
                        IntervalNoise* noise = nullptr) const;
  /// The process noise over node n's interval to the next node (Node::noise), from the chain of
  /// its preintegrations forward (which must reach the next node); R: the attitude at the node.
  void intervalNoise(const Node& n, const Mat3& R, IntervalNoise& N) const;
  /// The larger extra noise variances (gyro [(rad/s)^2], accelerometer [(m/s^2)^2]) of samples j
  /// and j + 1 (addImu).
  void stepExtraVariances(std::size_t j, double& vg, double& va) const;
  /// F P F^T plus the process noise from node n to the next, on the components updated (all 19:
  /// full).
  MatS propagateCovariance(const IntegrationJacobian& F, const MatS& P, const Node& n,
                           bool full = false) const;
  /// lidarVelocity() with R_bl = R_bl_ Exp(x.phi_bl) and, for J, J_r(x.phi_bl) given; cache (if
  /// given): the IMU along the integration, as imuAlong() keeps it, and the motion at its end
  /// (motionAt()). The IMU is integrated to
  /// the LiDAR time with the clock offset dt_ref; the state's offset enters as its difference
  /// from dt_ref times the motion's rate (motionAt()), the model's derivative and the column
  /// alike, so that a Gauss-Newton solve converges; not at all where !offset_moves (a sensor
  /// standing still sees the same returns whatever the offset).
  /// chain (if given): the node at sample k, whose intervals span several samples: integrated
  /// across them (integrateAcross) with its caches, the whole intervals through pre, the gyro
  /// of the lever-arm term its fit (Node::gyro_fit).
  Vec3 lidarVelocity(const FilterState& x, const std::vector<ImuSample>& imu, std::size_t k,
                     double tau, double dt_ref, bool offset_moves, const Mat3& R_bl,
                     const Mat3* Jr_phi, Eigen::Matrix<double, 3, kStateDim>* J, FitInstant* cache,
                     const Node* chain = nullptr, PreintegrationChains* pre = nullptr) const;
  void buildRows(Node& n) const;
  /// The gyro samples whose noise reaches a node's polynomial through the interpolation (k - 2
  /// .. k + 2), and dQ/dn for their noise (column block j: sample k - 2 + j; fewer at the ends).
  static constexpr std::size_t kLeverSamples = 5;
  static constexpr int kLeverDim = 3 * static_cast<int>(kLeverSamples);
  using LeverNoise = Eigen::Matrix<double, 9, kLeverDim>;
  LeverNoise leverNoise(const Node& n) const;
  /// For a node whose intervals span several samples, the gyro in its lever-arm term is the
  /// least-squares polynomial in s = tau / h (tau the returns' time from the node's) through the
  /// samples within its interval of returns taken to the IMU's clock (t_j - t_k + dt_ref in
  /// [-before, after]; the one nearest its centre where none is) and the sample on either side
  /// of them, of degree 2 (the LiDAR velocity's) or less with fewer than three samples. So every
  /// sample's gyro noise reaches the nodes whose returns it covers, as with a node per sample,
  /// where three instants would read a dozen samples' (the boundaries' twice) and not the rest.
  /// coef (if given): [rad/s] the coefficients of 1, s, s^2; cov (if given): their covariance
  /// per unit gyro_sigma^2 (a sample the screen interpolated with its extra variance); complete
  /// (if given): the sample after the interval had arrived (later ones change nothing).
  void gyroFit(const Node& n, std::array<Vec3, 3>* coef, Mat3* cov, bool* complete = nullptr) const;
  /// E E^T of the node's lever-arm noise (leverNoise, or through gyroFit when its intervals span
  /// several samples).
  Mat9 leverCovariance(const Node& n) const;
  /// Takes the gyro noise carried through the lever arm out of node n's quadratic form (A, b)
  /// in Q (see the definition).
  void marginalizeLeverNoise(const Node& n, Mat9& A, Vec9& b) const;
  /// Kalman update of the error dx (prior mean dx_prior relative to x_lin, covariance P) with
  /// node n's rows linearized at x_lin: Q, G its velocity polynomial there and the polynomial's
  /// Jacobian (velocityPolynomial). Returns the posterior error relative to x_lin. full: on all
  /// 19 components even when the calibration is declared exact.
  VecS dopplerUpdate(const Node& n, const Vec9& Q, const Mat9xS& G, const VecS& dx_prior, MatS& P,
                     bool full) const;
  /// Rest update of the error dx (relative to x_lin, covariance P) at node n.
  VecS restUpdate(const Node& n, const Vec3& gyro, const FilterState& x_lin, const VecS& dx,
                  MatS& P, bool full = false) const;
  /// The update of the first D components with R whitened rows r0 + H dx (H: their columns).
  template <int D, int R>
  static VecS kalmanUpdate(const Eigen::Matrix<double, R, D>& H,
                           const Eigen::Matrix<double, R, 1>& r0, const VecS& dx_prior, MatS& P);

  DopplerInertialFilterParams params_;
  Mat3 R_bl_;
  Vec3 p_bl_;
  std::vector<ImuSample> imu_;
  std::vector<RunningSums> imu_sums_{RunningSums{}};  ///< of imu_ (motionAt())
  /// Per sample of imu_: the variance added to gyro_sigma^2, accel_sigma^2 (addImu); empty
  /// while every sample given is a measured one.
  std::vector<Eigen::Vector2f> imu_extra_var_;
  std::vector<Node> nodes_;
  /// Nodes a smoothing has already been through (the first smoothed_ of nodes_): the later ones
  /// start the next smoothing from the propagation of the last smoothed one (smooth()).
  std::size_t smoothed_ = 0;
  /// [s] A node's dt_ref is moved to the smoothed offset when they differ by more than this.
  static constexpr double kOffsetRefStep = 5e-4;
  /// smooth()'s filtered and predicted covariances per node, kept from one smoothing to the
  /// next (a few hundred kilobytes: allocated anew, every smoothing touched fresh pages).
  std::vector<MatS> smoother_P_f_, smoother_P_p_;
  /// The linearization of smooth()'s last iteration (after smooth(.., ahead): of its pass made
  /// ahead, at the states it left), node by node, and for how many nodes it holds (0: none; set
  /// when a smoothing converges, for testCalibration()).
  std::vector<Linearization> linearization_;
  std::size_t linearized_ = 0;
  /// smooth()'s filtered and predicted means per node (its last forward pass, as the covariances
  /// above), and for how many of the first nodes a forward pass made around their current states
  /// (smooth(.., ahead)) still holds: their data have not changed since.
  std::vector<VecS> smoother_dx_f_, smoother_dx_p_;
  std::size_t forward_kept_ = 0;
  /// Node k's data (its returns, rows or rest) change: the kept forward pass holds before it
  /// only. Every change of a node's data calls it (beginNode, update, updateRest,
  /// cancelRestFrom, removePoint).
  void nodeChanged(std::size_t k) {
    forward_kept_ = std::min(forward_kept_, k);
    if (k < test_kept_.nodes) test_kept_.nodes = 0;
  }
  /// testCalibrationAhead()'s pass: its prior's std, the mean and covariance after the update of
  /// its last node (nodes - 1, 0: none kept) and that node's linearization point.
  struct KeptCalibrationPass {
    std::size_t nodes = 0;
    double rotation_sigma = 0, time_sigma = 0;
    VecS dx = VecS::Zero();
    MatS P = MatS::Zero();
    FilterState x;
  };
  KeptCalibrationPass test_kept_;
  /// The calibration test's prior (testCalibration()) at the linearization point x0.
  void calibrationPrior(const FilterState& x0, double rotation_sigma, double time_sigma, VecS& dx,
                        MatS& P) const;
  /// The calibration test's pass over nodes [from, to) (each node's update, the transitions
  /// between them) around lin (indexed by node), from dx and P at node from's prediction.
  void calibrationPass(const Linearization* lin, std::size_t from, std::size_t to, VecS& dx,
                       MatS& P) const;
  /// Moves the nodes' dt_ref to their offsets where those moved away (kOffsetRefStep), and makes
  /// again the lever-arm gyro's fits (and the rows) that moved or lacked samples.
  void referOffsets();
  /// r_doppler_ and lever_ratio_ from params_.
  void noiseChanged();
  FilterState x0_prior_;
  StartPrior prior_;
  OpenReturns open_;
  // The open node's prediction for gating, and the Jacobian of q_open_ (the linearization of
  // the node's first solve, at the same state).
  Vec9 q_open_ = Vec9::Zero();
  Mat9xS G_open_ = Mat9xS::Zero();
  Mat3 M_open_ = Mat3::Zero();  ///< covariance of q0 (v_l at the node) from the prediction
  double gate_speed_open_ = 0;  ///< [m/s] the gate's share of the LiDAR speed
  bool node_open_ = false;      ///< between beginNode() and update()
  /// Components the filter and smoother update: 15 (calibration exact), 16 (the clock offset
  /// estimated) or 19 (the rotation too).
  int active_ = kStateDim;
  double before_ = 0, after_ = 0;
  double gate_min2_ = 0, gate_k2_ = 0, r_doppler_ = 0;
  Mat3 lever_noise_ = Mat3::Zero();  ///< d v_l / d n_g: the gyro noise through the lever arm
  double lever_ratio_ = 0;           ///< doppler_sigma^2 / gyro_sigma^2 (0: no such noise)
  double forward_rss_ = 0;           ///< forwardResiduals()
  std::size_t forward_returns_ = 0;
};

}  // namespace freeinit
