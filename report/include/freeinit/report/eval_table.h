// The evaluation table: one row per (input, seed, method) with the errors against ground truth,
// the Cramer-Rao bound of the run and the NEES of its covariance, written as CSV (one row per run,
// loads back with readEvalCsv) and as Markdown: the paper's Tables I/II layout (inputs as
// columns, a block of methods per metric), then the errors against the physical limit (error /
// bound, NEES, statuses, confident wrong answers).
#pragma once

#include <freeinit/eval/bound_ratio.h>

#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace freeinit::report {

inline constexpr double kNoValue = std::numeric_limits<double>::quiet_NaN();

/// [deg] The reported gravity bound is atan(|b_a,true horizontal| / g) plus this margin, as in
/// tests/test_free_init_accuracy.cpp (the horizontal bias is not observable at rest or cruising).
inline constexpr double kGravityBoundMarginDeg = 0.1;

/// One sensor's white noise in a run: what the estimator was handed, the truth, and what the
/// estimator reports it to be. NaN where unknown.
struct SensorNoise {
  double declared = kNoValue;  ///< handed to the estimator (its configuration)
  /// The simulated unit's noise: for the IMU the RMS over its axes' sigmas (what one isotropic
  /// sigma estimated from the data converges to).
  double truth = kNoValue;
  /// What the estimator reports it used, and that figure's relative 1-sigma (InitResult does not
  /// report a noise yet: NaN until it does; makeEvalRow is where it will be read).
  double reported = kNoValue;
  double reported_rel_sigma = kNoValue;
};

/// One initialization of one method on one input, with its errors against ground truth.
/// Errors are NaN when the method gave no state (status not "ok") or the truth lacks them.
struct EvalRow {
  std::string source;                   ///< simulator preset or rawlog file
  int seed = 0;                         ///< simulator seed; 0 for a rawlog
  std::string method;                   ///< "free-init", "fast-lio2", "dlio", "doppler-ls"
  std::string status = "ok";            ///< "ok" or the InitStatus name
  double speed = kNoValue;              ///< [m/s] true body speed at the state time
  double velocity_err = kNoValue;       ///< [m/s] |v_b - v_b,true| at the state time
  double gravity_err_deg = kNoValue;    ///< [deg] gravity direction in the body frame
  double gravity_bound_deg = kNoValue;  ///< [deg] what the unobservable horizontal b_a implies
  double gyro_bias_err = kNoValue;      ///< [rad/s]
  double accel_bias_err = kNoValue;     ///< [m/s^2]
  double position_err = kNoValue;       ///< [m] displacement over the window (start body frame)
  double time_ms = kNoValue;            ///< [ms] wall time of this initialization
  // The Cramer-Rao bound of the run's window (sqrt of each block's trace); NaN without one (no
  // state, or an input without point labels).
  double crb_velocity = kNoValue;     ///< [m/s]
  double crb_gravity_deg = kNoValue;  ///< [deg]
  double crb_gyro_bias = kNoValue;    ///< [rad/s]
  double crb_accel_bias = kNoValue;   ///< [m/s^2]
  // NEES of the state's own covariance: velocity 3 dof, tilt 2, b_g 3, b_a 3. NaN without a state.
  double nees_velocity = kNoValue;
  double nees_tilt = kNoValue;
  double nees_gyro_bias = kNoValue;
  double nees_accel_bias = kNoValue;
  // The state's own standard deviations, as the bound is given (sqrt of each block's trace):
  // no estimator can be surer than the bound, so an own sigma below it is a covariance that
  // claims more than the data hold. NaN without a state.
  double sigma_velocity = kNoValue;     ///< [m/s]
  double sigma_gravity_deg = kNoValue;  ///< [deg]
  double sigma_gyro_bias = kNoValue;    ///< [rad/s]
  double sigma_accel_bias = kNoValue;   ///< [m/s^2]
  bool failed = false;                  ///< set by markFailures
  std::string failure;                  ///< why, when failed
  int warnings = 0;                     ///< warnings of an ok state (InitialState::warnings)
  /// The calibration handed to the estimator was wrong on purpose (a randomized scenario's
  /// undeclared time offset or extrinsics error): such a run must be within 3x its bound, flagged
  /// (a warning or a status), never a plain ok that is wrong.
  bool wrong_calibration = false;
  /// [s] how long the state used the knowledge of rest (zero velocity and rate, or the rate
  /// alone, while the IMU showed rest; Diagnostics::static_duration, zero_rate_duration), NaN
  /// without a state. The bound does not know of rest: an own sigma below it is then no
  /// contradiction.
  double rest_duration = kNoValue;

  // What the estimator was handed against the truth (freeinit-eval: --imu-noise-factor,
  // --doppler-noise-factor, --time-offset); NaN where unknown (a rawlog).
  /// The group of runs this row is summarized in (summarize()): the misdeclaration it was handed,
  /// e.g. "imu×0.25 doppler×1"; empty: one group per method.
  std::string block;
  double imu_noise_factor = kNoValue;      ///< [-] the IMU's datasheet noise / declared
  double doppler_noise_factor = kNoValue;  ///< [-] the Doppler's datasheet noise / declared
  SensorNoise noise_gyro;                  ///< [rad/s] per sample
  SensorNoise noise_accel;                 ///< [m/s^2] per sample
  SensorNoise noise_doppler;               ///< [m/s] per point
  double time_offset_true = kNoValue;      ///< [s] LiDAR clock minus IMU clock in the recording
  /// [s] The clock offset the estimator reports and its sigma (not reported yet: NaN).
  double time_offset_reported = kNoValue;
  double time_offset_reported_sigma = kNoValue;
  /// [rad/s] The gyro-bias bound of an estimator that knows of the window's rest
  /// (eval::Bound::gyro_bias_zero_rate); NaN without a bound or without rest in the window.
  double crb_gyro_bias_zero_rate = kNoValue;
  int window_samples = -1;  ///< IMU samples of the bound's window; -1 without a bound
  int rest_samples = -1;    ///< of which at rest by the truth; -1 without a bound

  // error / bound (eval::boundRatio): NaN without a state or a bound.
  double ratioVelocity() const { return eval::boundRatio(velocity_err, crb_velocity); }
  double ratioGravity() const { return eval::boundRatio(gravity_err_deg, crb_gravity_deg); }
  double ratioGyroBias() const { return eval::boundRatio(gyro_bias_err, crb_gyro_bias); }
  double ratioAccelBias() const { return eval::boundRatio(accel_bias_err, crb_accel_bias); }
  double ratioGyroBiasZeroRate() const {
    return eval::boundRatio(gyro_bias_err, crb_gyro_bias_zero_rate);
  }
  /// The truth is at rest over the whole window of the bound (a static start).
  bool staticWindow() const { return window_samples > 0 && rest_samples == window_samples; }
  /// The quantities of an ok state more than 3x their bound and above `floors` ("velocity",
  /// "gravity", "b_g", "b_a", comma-separated); empty when none.
  std::string confidentlyWrong(const eval::NoticeFloors& floors = {}) const;
};

/// The statuses a run can end with (InitStatus names, "ok" first).
const std::vector<std::string>& statusNames();

/// A run fails when its status is not "ok" or an error is above these thresholds.
struct FailureThresholds {
  double velocity = 0.2;     ///< [m/s]
  double gravity_deg = 2.0;  ///< [deg]
};

/// Sets `failed` and `failure` on every row.
void markFailures(std::vector<EvalRow>& rows, const FailureThresholds& thresholds);

/// All of `s` as a number (std::stod's syntax); nullopt when it is empty, not a number, out of
/// double's range, or anything is left over ("2x").
std::optional<double> parseDouble(const std::string& s);

/// CSV with a header line; text fields quoted when needed, missing values empty. The ratio and
/// confident_wrong columns are derived (readEvalCsv checks their syntax and recomputes them).
/// Atomic write.
void writeEvalCsv(const std::string& path, const std::vector<EvalRow>& rows);
/// Reads what writeEvalCsv wrote. Throws std::runtime_error naming the file and line on bad input.
std::vector<EvalRow> readEvalCsv(const std::string& path);

/// Statistics of one method over its runs. The error/bound ratios, NEES shares and confident wrong
/// answers are over the ok runs with a correct calibration; the runs handed a wrong one are
/// counted apart.
/// An own sigma below this share of the Cramer-Rao bound is counted as claiming more than the
/// data hold (the share leaves room for the bound's own linearization, a few per cent).
inline constexpr double kOwnSigmaBelowBound = 0.95;
/// A reported noise is compared with the truth when its own relative sigma is at most this (the
/// window held enough samples to tell), and counted right within kReportedNoiseTolerance of it.
inline constexpr double kReportedNoiseResolved = 0.07;
inline constexpr double kReportedNoiseTolerance = 0.20;

struct MethodSummary {
  std::string method;
  std::string block;  ///< EvalRow::block of its runs
  /// "method" or "method · block".
  std::string label() const { return block.empty() ? method : method + " · " + block; }
  int runs = 0;
  std::vector<int> status_counts;  ///< per statusNames(), then one for any other status
  int with_bound = 0;              ///< ok runs with a bound
  /// Median and 95th percentile of error / bound over the ok runs with a bound, per quantity
  /// (velocity, gravity, b_g, b_a); NaN when there is none.
  double ratio_median[4] = {kNoValue, kNoValue, kNoValue, kNoValue};
  double ratio_p95[4] = {kNoValue, kNoValue, kNoValue, kNoValue};
  /// Ok runs with a NEES above the 99.9 % chi-square quantile, per block (velocity, tilt, b_g,
  /// b_a), and the ok runs with a NEES.
  int nees_above[4] = {0, 0, 0, 0};
  int with_nees = 0;
  /// Ok runs whose own sigma is below kOwnSigmaBelowBound times the bound, per block, and the ok
  /// runs with both that did not use the knowledge of rest.
  int sigma_below_bound[4] = {0, 0, 0, 0};
  int with_sigma = 0;
  int confident_wrong = 0;  ///< ok runs with a correct calibration and a confident wrong quantity
  /// Ok runs whose window is at rest throughout (EvalRow::staticWindow) with a zero-rate bound, of
  /// which those with a b_g error above eval::kConfidentWrongRatio times it, and the median and
  /// 95th percentile of b_g error / zero-rate bound over them.
  int static_starts = 0;
  int static_gyro_bias_above_zero_rate = 0;
  double zero_rate_ratio_median = kNoValue;
  double zero_rate_ratio_p95 = kNoValue;
  /// Per sensor (gyro, accel, Doppler): ok runs with a reported noise whose relative sigma is at
  /// most kReportedNoiseResolved and a truth, and of those the ones within
  /// kReportedNoiseTolerance of the truth.
  int noise_resolved[3] = {0, 0, 0};
  int noise_within[3] = {0, 0, 0};
  /// Ok runs with a reported clock offset and sigma, and of those within 3 sigma of the truth.
  int time_offset_reported = 0;
  int time_offset_within = 0;
  // The runs handed a wrong calibration (not in the ratios, NEES shares or confident_wrong above):
  int wrong_calibration_runs = 0;
  int wrong_calibration_ok = 0;           ///< of which status ok
  int wrong_calibration_flagged = 0;      ///< ok with a warning, and confidently wrong
  int wrong_calibration_plain_wrong = 0;  ///< ok without a warning and confidently wrong
};

/// One summary per method and block (EvalRow::block): the methods in order of first appearance,
/// each method's blocks in natural order (numbers in the labels compared by value).
std::vector<MethodSummary> summarize(const std::vector<EvalRow>& rows,
                                     const eval::NoticeFloors& floors = {});

/// The p-quantile (0..1) of `values` (linear interpolation between order statistics); NaN when
/// empty.
double quantile(std::vector<double> values, double p);

/// Markdown: error / bound per method (median, 95th percentile), the share of ok runs with a NEES
/// above the 99.9 % chi-square quantile, the count of every status, the bound itself per input,
/// and the list of confident wrong answers (at most `max_listed` per method, then a count).
std::string boundsMarkdown(const std::vector<EvalRow>& rows, const eval::NoticeFloors& floors = {},
                           std::size_t max_listed = std::numeric_limits<std::size_t>::max());

/// The per-method summaries as CSV (one row per method). Atomic write.
void writeSummaryCsv(const std::string& path, const std::vector<EvalRow>& rows,
                     const eval::NoticeFloors& floors = {});

/// The summary in the paper's layout: one column per input (worst over seeds; time: mean), one
/// row per method in each metric block, a "failed runs" block. "×" after a value: over its
/// threshold on every seed ("×k/n": on k of n); "×" alone: no run gave a state.
std::string markdownSummary(const std::vector<EvalRow>& rows, const FailureThresholds& thresholds);

/// A Markdown report: `command` that produced it, the thresholds, the summary, the errors against
/// the bound (boundsMarkdown) and every run. Atomic write.
void writeEvalMarkdown(const std::string& path, const std::vector<EvalRow>& rows,
                       const FailureThresholds& thresholds, const std::string& command);

}  // namespace freeinit::report
