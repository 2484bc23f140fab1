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
#include <utility>

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

/// What every method is given: the same input, on equal terms.
struct MethodInput {
  const FreeInitConfig& config;  ///< with the input's extrinsics
  const std::vector<ImuSample>& imu;
  const std::vector<LidarFrame>& frames;
  const Extrinsics& extrinsics;
  const MethodOptions& options;
  /// The IMU samples of Free-Init's window (one more than there are when the IMU does not cover
  /// it), which the baselines of a fixed sample count are given.
  int window = 0;
};

/// One method of the evaluation: how it runs (timed) and what it reports as its velocity track.
struct Method {
  const char* name;
  bool baseline;  ///< skipped when MethodOptions::baselines is off
  InitResult (*run)(const MethodInput&);
  void (*track)(const MethodInput&, MethodRun&);
  bool track_per_frame;  ///< the track is one fit per frame (plotted as markers)
};

InitResult runFreeInit(const MethodInput& in) {
  return FreeInit::run(in.config, in.imu, in.frames);
}

InitResult runFastLio2(const MethodInput& in) { return baselines::fastLio2(in.imu, in.window); }

InitResult runDlio(const MethodInput& in) {
  return baselines::dlio(in.imu, in.options.dlio_duration);
}

InitResult runDopplerLeastSquares(const MethodInput& in) {
  return baselines::dopplerLeastSquares(in.imu, in.frames, in.extrinsics, in.window);
}

/// Free-Init's velocimeter at every IMU sample.
void velocimeterTrack(const MethodInput&, MethodRun& m) {
  for (const VelocitySample& v : m.result.velocities) m.track.push_back({v.t, v.v_b});
}

/// A static-mean initializer reports v = 0 over its window (its trajectory).
void zeroVelocityTrack(const MethodInput&, MethodRun& m) {
  if (!m.result.state.ok()) return;
  for (const PoseSample& p : m.result.trajectory) m.track.push_back({p.t, Vec3::Zero()});
}

/// The Doppler least squares on every frame that starts inside the window, as the method would
/// report them.
void perFrameDopplerTrack(const MethodInput& in, MethodRun& m) {
  if (in.imu.empty() || in.imu.size() < static_cast<std::size_t>(in.window)) return;
  const double t_end = in.imu[static_cast<std::size_t>(in.window) - 1].t;
  for (const LidarFrame& f : in.frames) {
    if (f.stamp < in.imu.front().t || f.stamp > t_end) continue;
    const auto fv = baselines::dopplerFrameVelocity(f, in.imu, in.extrinsics);
    if (fv.ok()) m.track.push_back({fv.t_mid, fv.v_b});
  }
}

/// The methods in the order of the tables. A new baseline is a run function (and, if its track
/// is not one of these, a track function) and one line here.
constexpr Method kMethods[] = {
    {"free-init", false, runFreeInit, velocimeterTrack, false},
    {"fast-lio2", true, runFastLio2, zeroVelocityTrack, false},
    {"dlio", true, runDlio, zeroVelocityTrack, false},
    {"doppler-ls", true, runDopplerLeastSquares, perFrameDopplerTrack, true},
};

}  // namespace

std::vector<MethodRun> runMethods(const FreeInitConfig& config, const std::vector<ImuSample>& imu,
                                  const std::vector<LidarFrame>& frames,
                                  const Extrinsics& extrinsics, const MethodOptions& options) {
  FreeInitConfig cfg = config;
  cfg.extrinsics = extrinsics;
  const auto last = windowLastSample(imu, 0, cfg.window.duration);
  const int window = static_cast<int>(last ? *last + 1 : imu.size() + 1);
  const MethodInput in{cfg, imu, frames, extrinsics, options, window};
  std::vector<MethodRun> runs;
  for (const Method& method : kMethods) {
    if (method.baseline && !options.baselines) continue;
    runs.push_back(timed(method.name, [&] { return method.run(in); }));
    MethodRun& m = runs.back();
    m.track_per_frame = method.track_per_frame;
    method.track(in, m);
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
  // The knowledge of rest the bound does not have: zero velocity, or zero rotation rate only.
  row.rest_duration = std::max(r.diag.static_duration, r.diag.zero_rate_duration);
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
  const eval::OwnSigmas own = eval::ownSigmas(r.state);
  row.sigma_velocity = own.velocity;
  row.sigma_gravity_deg = own.gravity_deg;
  row.sigma_gyro_bias = own.gyro_bias;
  row.sigma_accel_bias = own.accel_bias;
  // The clock offset the method reported, and the noise it read from the data (a configured
  // value passed on is no report of the sensor's noise: NaN).
  if (r.state.ok()) {
    row.time_offset_reported = r.state.time_offset;
    row.time_offset_reported_sigma = r.state.time_offset_sigma;
  }
  const std::pair<SensorNoise*, const NoiseUsed*> noises[] = {
      {&row.noise_gyro, &r.diag.noise.gyro},
      {&row.noise_accel, &r.diag.noise.accel},
      {&row.noise_doppler, &r.diag.noise.doppler}};
  for (const auto& [to, from] : noises) {
    if (from->source == NoiseUsed::Source::Declared) continue;
    to->reported = from->value;
    to->reported_rel_sigma = from->rel_sigma;
  }
  if (bound && bound->ok) {
    row.crb_velocity = bound->velocity;
    row.crb_gravity_deg = bound->gravity_deg;
    row.crb_gyro_bias = bound->gyro_bias;
    row.crb_accel_bias = bound->accel_bias;
    row.crb_gyro_bias_zero_rate = bound->gyro_bias_zero_rate;
    row.window_samples = static_cast<int>(bound->nodes);
    row.rest_samples = static_cast<int>(bound->rest_nodes);
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
