// Runs Free-Init and the baseline initializers on one input, on equal terms (same IMU, frames,
// extrinsics and window length), timing each, and turns their results into evaluation rows.
#pragma once

#include <freeinit/config.h>
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
/// least squares of the last frame in that window.
std::vector<MethodRun> runMethods(const FreeInitConfig& config, const std::vector<ImuSample>& imu,
                                  const std::vector<LidarFrame>& frames,
                                  const Extrinsics& extrinsics, const MethodOptions& options);

/// A true body pose.
struct PoseTruth {
  Mat3 R_wb = Mat3::Identity();
  Vec3 p_w = Vec3::Zero();  ///< [m]
};

/// The true state at one instant, as the simulator and a truth file beside a rawlog give it.
struct StateTruth : PoseTruth {
  Vec3 v_w = Vec3::Zero();  ///< [m/s] body velocity in w
  Vec3 g_w = Vec3(0, 0, -kGravity);
  Vec3 b_g = Vec3::Zero();  ///< [rad/s]
  Vec3 b_a = Vec3::Zero();  ///< [m/s^2]
  Vec3 v_b() const { return R_wb.transpose() * v_w; }
  Vec3 g_b() const { return R_wb.transpose() * g_w; }
};

/// The truth at a UNIX time [s]; may throw when the time is not covered.
using TruthFn = std::function<StateTruth(double)>;

/// The evaluation row of one method's run on `source` (seed 0 for a rawlog): its status and wall
/// time and, when it gave a state, its errors against `truth` at the state time (velocity,
/// gravity direction and biases in the body frame, the gravity bound of the true horizontal
/// accelerometer bias plus kGravityBoundMarginDeg) and its displacement error over the window.
EvalRow makeEvalRow(const std::string& source, int seed, const MethodRun& run,
                    const TruthFn& truth);

/// Error [m] of the displacement over the initialization window expressed in the body frame at
/// its start, R_wb(t0)^T (p_w(t1) - p_w(t0)), t0 the first pose of r.trajectory and t1 the state
/// time: free of the world-frame choice. NaN without a state or a trajectory.
double displacementError(const InitResult& r, const PoseTruth& at_start, const PoseTruth& at_end);

/// Runs `job(i)` for i in [0, count) on `threads` threads (0: hardware concurrency). Each index
/// runs exactly once, in no particular order; after all threads end, the exception of the lowest
/// failing index (if any) is rethrown. If a thread cannot be started, the threads already
/// started finish their current jobs and that error is rethrown (not every index has run).
void parallelFor(std::size_t count, unsigned threads, const std::function<void(std::size_t)>& job);

}  // namespace freeinit::report
