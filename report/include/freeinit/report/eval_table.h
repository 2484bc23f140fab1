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
  /// [s] how long the state used the knowledge of rest (zero velocity and rate while the IMU
  /// showed rest; Diagnostics::static_duration), NaN without a state. The bound does not know of
  /// rest: an own sigma below it is then no contradiction.
  double rest_duration = kNoValue;

  // error / bound (eval::boundRatio): NaN without a state or a bound.
  double ratioVelocity() const { return eval::boundRatio(velocity_err, crb_velocity); }
  double ratioGravity() const { return eval::boundRatio(gravity_err_deg, crb_gravity_deg); }
  double ratioGyroBias() const { return eval::boundRatio(gyro_bias_err, crb_gyro_bias); }
  double ratioAccelBias() const { return eval::boundRatio(accel_bias_err, crb_accel_bias); }
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

struct MethodSummary {
  std::string method;
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
  // The runs handed a wrong calibration (not in the ratios, NEES shares or confident_wrong above):
  int wrong_calibration_runs = 0;
  int wrong_calibration_ok = 0;           ///< of which status ok
  int wrong_calibration_flagged = 0;      ///< ok with a warning, and confidently wrong
  int wrong_calibration_plain_wrong = 0;  ///< ok without a warning and confidently wrong
};

/// One summary per method, in order of first appearance.
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
