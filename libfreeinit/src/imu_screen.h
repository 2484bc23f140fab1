// The IMU stream as the estimator integrates it: gross faults (a sample no motion explains)
// replaced by the value its neighbours imply, short gaps bridged, each such sample with the noise
// of its interpolation; never integrated at face value.
#pragma once

#include <freeinit/types.h>

#include <cstddef>
#include <vector>

namespace freeinit::detail {

/// What the screen tests against. Units as in ImuScreenParams' INI keys ([imu]).
struct ImuScreenParams {
  double gyro_range = 34.9;      ///< [rad/s] per axis: a reading at or beyond it is a fault
  double accel_range = 156.9;    ///< [m/s^2] per axis
  double fault_sigmas = 8.0;     ///< [-] the neighbours test's threshold in robust sigmas
  double gyro_sigma = 0.002;     ///< [rad/s] white noise per sample (the scale's floor)
  double accel_sigma = 0.02;     ///< [m/s^2]
  double max_bridged_gap = 0.1;  ///< [s] longer gaps are left open (the window declines)
};

/// A sample taken out of the stream.
struct ImuFault {
  double t = 0;               ///< [s] its time
  bool accel = false;         ///< the accelerometer's reading (else the gyro's)
  double magnitude = 0;       ///< [rad/s or m/s^2] |reading - value the neighbours imply|
  bool out_of_range = false;  ///< beyond gyro_range / accel_range
};

/// An interval without samples, longer than 2.5 nominal intervals.
struct ImuGap {
  double t = 0;             ///< [s] the last sample before it
  double length = 0;        ///< [s] to the first sample after it
  std::size_t missing = 0;  ///< samples missing at the nominal rate
  bool bridged = false;     ///< synthetic samples fill it (length <= max_bridged_gap)
};

/// What a sample's value adds to the IMU's white noise: 0 for a measured one; for a synthetic
/// one (interpolated in place of a fault or within a bridged gap) the variance of its
/// interpolation's error. Absolute, so that it holds whatever white noise the estimator uses.
struct ImuExtraNoise {
  float gyro = 0.0f;             ///< [(rad/s)^2] per axis
  float accel = 0.0f;            ///< [(m/s^2)^2] per axis
  bool gyro_synthetic = false;   ///< the gyro reading is not a measurement
  bool accel_synthetic = false;  ///< the accelerometer's likewise
  bool synthetic() const { return gyro_synthetic || accel_synthetic; }
};

/// Screens a growing IMU stream. advance() takes the samples received so far (the sequencer's,
/// in time order) and appends to samples() those it can decide: sample j once j + kMaxRun + 2
/// has arrived (its tests look that far ahead) or the stream has ended.
///
/// Per sample and sensor (gyro, accelerometer):
///  - range: a component at or beyond the range (a saturated or corrupted packet) is a fault;
///  - neighbours: r = y_j - the cubic through j-2, j-1, j+1, j+2 at t_j (white noise: var 1.94
///    sigma^2 at a constant rate). Nothing more to test while every axis' |r| is within the
///    smallest threshold the robust sigma can give. Else a fault when one axis' |r| exceeds
///    fault_sigmas robust sigmas s of r over the last 40 samples (1.4826 MAD, at least 1.4 sigma:
///    it adapts to vibration) plus a physical floor (0.5 m/s^2, 0.05 rad/s), and the linear
///    extrapolations from either side both miss it by half that with the same sign: a lone
///    spike, not a step of the motion (a step leaves one side's extrapolation right);
///  - runs: faults in a row leave the first one no clean pair on its right (two equal spikes
///    look like a step to the test above). So the test is repeated with the right pair moved
///    past a run of L = 1..kMaxRun samples (j+L, j+L+1): the run is faulty when each of its
///    samples is out of range or a spike against that cubic and both sides' extrapolations.
///    The right pair must be in range and clean: j+L within the threshold of the cubic through
///    j-2, j-1, j+L+1, j+L+2 (an interpolation: a linear extrapolation misses a vibrating
///    platform by far more), so that no replacement is built from a faulty or out-of-range
///    neighbour (the left pair is screened already). Each sample of a run is then decided, and
///    counted, in its turn. A run beyond kMaxRun cannot be told from a step of the motion (the
///    estimator's acceptance test is the backstop for what the screen lets through).
/// A faulty reading is replaced by that cubic's value with the extra variance of the
/// interpolation's error: sigma^2 sum_i w_i^2 from the noise of the nodes (Lagrange weights
/// w_i at t_j; a left node that is itself a replacement adds w_i^2 times its own extra
/// variance) plus the motion the cubic misses, m^2 (P(t_j) / P_1)^2, with P(t) = prod_i
/// (t - t_i), P_1 = 4 h^4 its value for a lone sample at the nominal rate and m^2 = s^2 - 1.94
/// sigma^2 the part of the residual's variance that is not white noise. For a lone sample at
/// the nominal rate that is s^2 - sigma^2: s^2 counts the sample's own noise and the fit's, and
/// only the fit's is the replacement's. Where no cubic can be built (the stream's ends, next to
/// a gap, an out-of-range run beyond kMaxRun) the nearest screened value is held, with s^2 +
/// (q d)^2, d the time from the sensor's last measurement and q the rate of change before it
/// plus the gaps' allowance.
///
/// Gaps: the nominal interval h is the median of the first 20 intervals. An interval beyond
/// 2.5 h is a gap; up to max_bridged_gap it is filled with samples at about h, valued on the line
/// between the samples on each side, with the extra variance (q d)^2 growing with the distance d
/// to the nearer measured sample (q: the rate of change across the gap plus 1 rad/s^2 or
/// 10 m/s^3). A line and not the cubic through two samples on each side: that cubic's slope at
/// either end comes from one noisy difference and carries it into the gap (at the middle of a
/// 10-interval gap its weights' squares sum to 7.9, the line's to 0.5: 2.8 sigma against 0.7),
/// and the motion it would follow is what (q d)^2 allows for. Longer gaps stay (the estimator
/// declines a window holding one).
class ImuScreen {
 public:
  /// The longest run of faulty samples the neighbours test recognizes.
  static constexpr std::size_t kMaxRun = 3;

  explicit ImuScreen(const ImuScreenParams& p) : p_(p) {}

  /// Screens the samples of `raw` not yet decided; `finished`: no more will come.
  void advance(const std::vector<ImuSample>& raw, bool finished);

  /// The screened stream (synthetic samples included), times increasing.
  const std::vector<ImuSample>& samples() const { return out_; }
  /// Per screened sample, the variance its value adds to the IMU's white noise.
  const std::vector<ImuExtraNoise>& extraNoise() const { return extra_; }
  /// [s] the nominal sample interval at the last sample decided (0 until known): the median of
  /// the 20 intervals up to 5 samples after it, so that a driver's burst or a change of rate
  /// moves it only where it happens.
  double interval() const { return h_; }
  const std::vector<ImuFault>& faults() const { return faults_; }
  const std::vector<ImuGap>& gaps() const { return gaps_; }

 private:
  void decide(std::size_t j);
  /// Screens sensor `accel` of sample j (`neighbours`: j's lone-sample test applies): whether it
  /// is a fault, and then its replacement and [unit^2] the replacement's extra variance.
  bool screenSensor(std::size_t j, bool accel, bool neighbours, Vec3& fit, double& extra_var);
  void bridge(std::size_t j);
  /// The robust sigma of the neighbours residual of sensor `accel`, floored.
  double robustSigma(bool accel) const;
  /// [s] the nominal interval about raw sample j (see interval()).
  double localInterval(std::size_t j) const;

  ImuScreenParams p_;
  std::vector<ImuSample> work_;  ///< the raw samples, faults replaced once decided
  std::vector<ImuSample> out_;
  std::vector<ImuExtraNoise> extra_;
  std::vector<ImuFault> faults_;
  std::vector<ImuGap> gaps_;
  std::vector<double> recent_g_, recent_a_;  ///< |r| components of the last samples (ring)
  std::size_t recent_n_ = 0;
  mutable std::vector<double> scratch_;  ///< robustSigma's copy of a ring
  std::size_t next_ = 0;                 ///< the next raw sample to decide
  double t_measured_[2] = {0, 0};        ///< [s] per sensor (gyro, accel): its last measurement
  bool measured_[2] = {false, false};    ///< t_measured_ is set
  /// Per sensor (gyro, accel), the extra variance of samples j - 1 and j - 2 (0: measured).
  double left_var_[2][2] = {{0, 0}, {0, 0}};
  /// Per sensor, [unit/s] the rate of change between the two measured samples before the
  /// last held one.
  double hold_rate_[2] = {0, 0};
  double h_ = 0;
};

}  // namespace freeinit::detail
