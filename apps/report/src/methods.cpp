#include <freeinit/baselines.h>
#include <freeinit/eval/state_errors.h>
#include <freeinit/free_init.h>
#include <freeinit/report/methods.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <mutex>
#include <thread>

namespace freeinit::report {
namespace {

template <typename F>
MethodRun timed(const char* method, F&& run) {
  MethodRun m;
  m.method = method;
  const auto t0 = std::chrono::steady_clock::now();
  m.result = run();
  m.time_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return m;
}

/// A static-mean initializer reports v = 0 over its window (its trajectory).
void zeroVelocityTrack(MethodRun& m) {
  if (!m.result.state.ok()) return;
  for (const PoseSample& p : m.result.trajectory) m.track.push_back({p.t, Vec3::Zero()});
}

}  // namespace

std::vector<MethodRun> runMethods(const FreeInitConfig& config, const std::vector<ImuSample>& imu,
                                  const std::vector<LidarFrame>& frames,
                                  const Extrinsics& extrinsics, const MethodOptions& options) {
  std::vector<MethodRun> runs;
  FreeInitConfig cfg = config;
  cfg.extrinsics = extrinsics;
  runs.push_back(timed("free-init", [&] { return FreeInit::run(cfg, imu, frames); }));
  for (const VelocitySample& v : runs.back().result.velocities)
    runs.back().track.push_back({v.t, v.v_b});
  if (!options.baselines) return runs;

  // The IMU samples of the window (more than there are when the IMU does not cover it).
  const auto last = windowLastSample(imu, 0, cfg.window.duration);
  const int window = static_cast<int>(last ? *last + 1 : imu.size() + 1);
  runs.push_back(timed("fast-lio2", [&] { return baselines::fastLio2(imu, window); }));
  zeroVelocityTrack(runs.back());
  runs.push_back(timed("dlio", [&] { return baselines::dlio(imu, options.dlio_duration); }));
  zeroVelocityTrack(runs.back());
  runs.push_back(timed("doppler-ls", [&] {
    return baselines::dopplerLeastSquares(imu, frames, extrinsics, window);
  }));
  // The same fit on every frame that starts inside the window, as the method would report them.
  MethodRun& d = runs.back();
  d.track_per_frame = true;
  if (!imu.empty() && imu.size() >= static_cast<std::size_t>(window)) {
    const double t_end = imu[static_cast<std::size_t>(window) - 1].t;
    for (const LidarFrame& f : frames) {
      if (f.stamp < imu.front().t || f.stamp > t_end) continue;
      const auto fv = baselines::dopplerFrameVelocity(f, imu, extrinsics);
      if (fv.ok()) d.track.push_back({fv.t_mid, fv.v_b});
    }
  }
  return runs;
}

EvalRow makeEvalRow(const std::string& source, int seed, const MethodRun& run, const TruthFn& truth,
                    const eval::Bound* bound) {
  const InitResult& r = run.result;
  EvalRow row;
  row.source = source;
  row.seed = seed;
  row.method = run.method;
  row.status = toString(r.state.status);
  row.time_ms = run.time_ms;
  if (!r.state.ok()) return row;
  row.warnings = static_cast<int>(r.state.warnings.size());
  const eval::StateTruth gt = truth(r.state.timestamp);
  const eval::StateErrors e = eval::stateErrors(r.state, gt);
  row.speed = e.speed;
  row.velocity_err = e.velocity;
  row.gravity_err_deg = e.gravity_deg;
  row.gravity_bound_deg = e.gravity_deg_from_bias + kGravityBoundMarginDeg;
  row.gyro_bias_err = e.gyro_bias;
  row.accel_bias_err = e.accel_bias;
  if (!r.trajectory.empty())
    row.position_err = eval::displacementError(r, truth(r.trajectory.front().t), gt);
  const eval::Nees n = eval::stateNees(r.state, gt);
  row.nees_velocity = n.velocity;
  row.nees_tilt = n.tilt;
  row.nees_gyro_bias = n.gyro_bias;
  row.nees_accel_bias = n.accel_bias;
  if (bound && bound->ok) {
    row.crb_velocity = bound->velocity;
    row.crb_gravity_deg = bound->gravity_deg;
    row.crb_gyro_bias = bound->gyro_bias;
    row.crb_accel_bias = bound->accel_bias;
  }
  return row;
}

void parallelFor(std::size_t count, unsigned threads, const std::function<void(std::size_t)>& job) {
  if (threads == 0) threads = std::max(1u, std::thread::hardware_concurrency());
  threads = static_cast<unsigned>(std::min<std::size_t>(threads, std::max<std::size_t>(count, 1)));
  std::atomic<std::size_t> next{0};
  std::exception_ptr error;  // of the lowest failing index, whatever the scheduling
  std::size_t error_index = count;
  std::mutex error_mutex;
  auto worker = [&] {
    for (std::size_t i = next++; i < count; i = next++) {
      try {
        job(i);
      } catch (...) {
        const std::lock_guard<std::mutex> lock(error_mutex);
        if (i < error_index) {
          error_index = i;
          error = std::current_exception();
        }
      }
    }
  };
  std::vector<std::thread> pool;
  auto join = [&] {
    for (auto& t : pool) t.join();
  };
  try {
    for (unsigned k = 1; k < threads; ++k) pool.emplace_back(worker);
  } catch (...) {
    // No thread (std::system_error) or no memory: the started threads must end before `pool`
    // goes (a joinable std::thread's destructor terminates). They run the jobs to the end.
    next = count;
    join();
    throw;
  }
  worker();
  join();
  if (error) std::rethrow_exception(error);
}

}  // namespace freeinit::report
