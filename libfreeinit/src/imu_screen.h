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

/// Relative noise of a sample: its white noise is scale times the IMU's (1: a measured sample).
struct ImuNoiseScale {
  float gyro = 1.0f, accel = 1.0f;
  bool synthetic() const { return gyro != 1.0f || accel != 1.0f; }
};

/// Screens a growing IMU stream. advance() takes the samples received so far (the sequencer's,
/// in time order) and appends to samples() those it can decide: sample j once j + 2 has arrived
/// (its test looks two samples to each side) or the stream has ended.
///
/// Per sample and sensor (gyro, accelerometer):
///  - range: a component at or beyond the range (a saturated or corrupted packet) is a fault;
///  - neighbours: r = y_j - the cubic through j-2, j-1, j+1, j+2 at t_j (white noise: var 1.94
///    sigma^2 at a constant rate). A fault when one axis' |r| exceeds fault_sigmas robust sigmas
///    of r over the last 40 samples (1.4826 MAD, at least 1.4 sigma: it adapts to vibration)
///    plus a physical floor (0.5 m/s^2, 0.05 rad/s), and the linear extrapolations from either
///    side both miss it by half that with the same sign: a lone spike, not a step of the motion
///    (a step leaves one side's extrapolation right).
/// A faulty reading is replaced by that cubic's value (the nearest neighbour's at the stream's
/// ends) with the noise scale sqrt(1.94 s^2 + sigma^2) / sigma, s the robust sigma; the filter
/// integrates it with that noise.
///
/// Gaps: the nominal interval h is the median of the first 20 intervals. An interval beyond
/// 2.5 h is a gap; up to max_bridged_gap it is filled with samples at about h, valued by the
/// cubic through the two samples on each side, with noise sigma^2 + (q d)^2 growing with the
/// distance d to the nearer measured sample (q: the rate of change across the gap plus 1 rad/s^2
/// or 10 m/s^3). Longer gaps stay (the estimator declines a window holding one).
class ImuScreen {
 public:
  explicit ImuScreen(const ImuScreenParams& p) : p_(p) {}

  /// Screens the samples of `raw` not yet decided; `finished`: no more will come.
  void advance(const std::vector<ImuSample>& raw, bool finished);

  /// The screened stream (synthetic samples included), times increasing.
  const std::vector<ImuSample>& samples() const { return out_; }
  /// Per screened sample, its noise relative to the IMU's.
  const std::vector<ImuNoiseScale>& noiseScales() const { return scale_; }
  /// [s] the nominal sample interval (0 until known).
  double interval() const { return h_; }
  const std::vector<ImuFault>& faults() const { return faults_; }
  const std::vector<ImuGap>& gaps() const { return gaps_; }

 private:
  void decide(std::size_t j);
  void bridge(std::size_t j);
  /// The robust sigma of the neighbours residual of sensor `accel`, floored.
  double robustSigma(bool accel) const;

  ImuScreenParams p_;
  std::vector<ImuSample> work_;  ///< the raw samples, faults replaced once decided
  std::vector<ImuSample> out_;
  std::vector<ImuNoiseScale> scale_;
  std::vector<ImuFault> faults_;
  std::vector<ImuGap> gaps_;
  std::vector<double> recent_g_, recent_a_;  ///< |r| components of the last samples (ring)
  std::size_t recent_n_ = 0;
  mutable std::vector<double> scratch_;  ///< robustSigma's copy of a ring
  std::size_t next_ = 0;                 ///< the next raw sample to decide
  double h_ = 0;
};

}  // namespace freeinit::detail
