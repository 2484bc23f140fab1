// Runs Free-Init and the baseline initializers on one input, on equal terms (same IMU, frames,
// extrinsics and window length), timing each, and turns their results into evaluation rows.
#pragma once

#include <freeinit/config.h>
#include <freeinit/eval/cramer_rao_bound.h>
#include <freeinit/eval/state_truth.h>
#include <freeinit/initial_state.h>
#include <freeinit/report/eval_table.h>

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace freeinit::report {

/// A velocity a method reports for an instant.
struct TimedVelocity {
  double t = 0;             ///< [s] UNIX
  Vec3 v_b = Vec3::Zero();  ///< [m/s] body velocity in b
};

/// One method's initialization of one input.
struct MethodRun {
  std::string method;  ///< "free-init", "fast-lio2", "dlio", "doppler-ls"
  InitResult result;
  double time_ms = 0;  ///< [ms] wall time
  /// What the method says the velocity is over time: Free-Init's velocimeter at every IMU sample;
  /// the static-mean baselines' v = 0 over their window; one per-frame fit per frame for the
  /// Doppler least squares (plotted as markers).
  std::vector<TimedVelocity> track;
  bool track_per_frame = false;
};

struct MethodOptions {
  bool baselines = true;       ///< also run the baselines
  double dlio_duration = 3.0;  ///< [s] DLIO's static calibration time
};

/// Runs Free-Init with `config` and (optionally) FAST-LIO2's static mean over the same number of
/// IMU samples as Free-Init's window, DLIO's mean over `dlio_duration`, and the per-frame Doppler
/// least squares of the last frame in that window, in this order (one table in methods.cpp: a
/// method is a run function, a track function and one line there).
std::vector<MethodRun> runMethods(const FreeInitConfig& config, const std::vector<ImuSample>& imu,
                                  const std::vector<LidarFrame>& frames,
                                  const Extrinsics& extrinsics, const MethodOptions& options);

/// The truth at a UNIX time [s]; may throw when the time is not covered.
using TruthFn = std::function<eval::StateTruth(double)>;

/// The evaluation row of one method's run on `source` (seed 0 for a rawlog): its status and wall
/// time and, when it gave a state, its errors against `truth` at the state time (eval::stateErrors:
/// velocity, gravity direction and biases in the body frame; the gravity bound of the true
/// horizontal accelerometer bias plus kGravityBoundMarginDeg), the NEES of its covariance
/// (eval::stateNees), its displacement error over the window and, when `bound` is given and ok,
/// the Cramer-Rao bound of its window (with its zero-rate gyro-bias bound and the window's samples
/// at rest). What the method was handed (noise, factors, offset) is the caller's to fill.
EvalRow makeEvalRow(const std::string& source, int seed, const MethodRun& run, const TruthFn& truth,
                    const eval::Bound* bound = nullptr);

/// Runs `job(i)` for i in [0, count) on `threads` threads (0: hardware concurrency). Each index
/// runs exactly once, in no particular order; after all threads end, the exception of the lowest
/// failing index (if any) is rethrown. If a thread cannot be started, the threads already
/// started finish their current jobs and that error is rethrown (not every index has run).
void parallelFor(std::size_t count, unsigned threads, const std::function<void(std::size_t)>& job);

}  // namespace freeinit::report
