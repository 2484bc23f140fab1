// The evaluation table: one row per (input, seed, method) with the errors against ground truth,
// written as CSV (one row per run, loads back with readEvalCsv) and as Markdown in the layout of
// the paper's Tables I/II (inputs as columns, a block of methods per metric).
#pragma once

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
  bool failed = false;                  ///< set by markFailures
  std::string failure;                  ///< why, when failed
};

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

/// CSV with a header line; text fields quoted when needed, missing values empty. Atomic write.
void writeEvalCsv(const std::string& path, const std::vector<EvalRow>& rows);
/// Reads what writeEvalCsv wrote. Throws std::runtime_error naming the file and line on bad input.
std::vector<EvalRow> readEvalCsv(const std::string& path);

/// The summary in the paper's layout: one column per input (worst over seeds; time: mean), one
/// row per method in each metric block, a "failed runs" block. "×" after a value: over its
/// threshold on every seed ("×k/n": on k of n); "×" alone: no run gave a state.
std::string markdownSummary(const std::vector<EvalRow>& rows, const FailureThresholds& thresholds);

/// A Markdown report: `command` that produced it, the thresholds, the summary and every run.
/// Atomic write.
void writeEvalMarkdown(const std::string& path, const std::vector<EvalRow>& rows,
                       const FailureThresholds& thresholds, const std::string& command);

}  // namespace freeinit::report
