#include <freeinit/config.h>
#include <freeinit/initial_state.h>

#include <cmath>
#include <stdexcept>
#include <string>

namespace freeinit {
namespace {

void require(bool ok, const char* key, const std::string& what) {
  if (!ok) throw std::invalid_argument(std::string("configuration key '") + key + "': " + what);
}
void positive(double v, const char* key) {
  require(std::isfinite(v) && v > 0, key, "must be > 0 (got " + std::to_string(v) + ")");
}
void nonNegative(double v, const char* key) {
  require(std::isfinite(v) && v >= 0, key, "must be >= 0 (got " + std::to_string(v) + ")");
}

}  // namespace

void FreeInitConfig::validate() const {
  const auto& e = estimator;
  positive(e.bootstrap_duration, "estimator.bootstrap_duration");
  require(e.bootstrap_points >= 10, "estimator.bootstrap_points", "must be >= 10");
  positive(e.initial_tilt_sigma, "estimator.initial_tilt_sigma");
  require(e.max_iterations >= 1, "estimator.max_iterations", "must be >= 1");
  nonNegative(e.accel_bias_random_walk, "estimator.accel_bias_random_walk");
  positive(e.rest_velocity_sigma, "estimator.rest_velocity_sigma");
  const auto& v = velocimeter;
  positive(v.doppler_sigma, "velocimeter.doppler_sigma");
  positive(v.gyro_sigma, "velocimeter.gyro_sigma");
  positive(v.vel_random_walk, "velocimeter.vel_random_walk");
  positive(v.omega_random_walk, "velocimeter.omega_random_walk");
  nonNegative(v.gyro_bias_random_walk, "velocimeter.gyro_bias_random_walk");
  positive(v.gyro_bias_tau, "velocimeter.gyro_bias_tau");
  positive(v.gyro_bias_sigma0, "velocimeter.gyro_bias_sigma0");
  require(v.gyro_bias_prior.allFinite(), "velocimeter.gyro_bias_prior", "must be finite");
  nonNegative(v.min_range, "velocimeter.min_range");
  require(v.max_range > v.min_range, "velocimeter.max_range", "must exceed min_range");
  require(v.point_stride >= 0, "velocimeter.point_stride", "must be >= 0 (0: automatic)");
  positive(v.max_point_rate, "velocimeter.max_point_rate");
  positive(v.gate_sigma, "velocimeter.gate_sigma");
  positive(v.gate_min, "velocimeter.gate_min");
  nonNegative(v.gate_rel, "velocimeter.gate_rel");
  require(bootstrap.points >= 10, "bootstrap.points", "must be >= 10");
  require(bootstrap.iterations >= 0, "bootstrap.iterations", "must be >= 0");
  positive(bootstrap.cauchy_scale, "bootstrap.cauchy_scale");
  positive(bootstrap.prior_sigma, "bootstrap.prior_sigma");
  nonNegative(bootstrap.min_info_eigen, "bootstrap.min_info_eigen");
  positive(static_detector.max_speed, "static_detector.max_speed");
  positive(static_detector.max_gyro_dev, "static_detector.max_gyro_dev");
  positive(static_detector.zupt_sigma, "static_detector.zupt_sigma");
  positive(static_detector.check_period, "static_detector.check_period");
  require(window.imu_samples >= 10, "window.imu_samples", "must be >= 10");
  require(window.refinement_passes >= 0, "window.refinement_passes", "must be >= 0");
  require(window.seed_pass_stride >= 1, "window.seed_pass_stride", "must be >= 1");
  require(window.seed_imu_samples == 0 || window.seed_imu_samples >= 10, "window.seed_imu_samples",
          "must be 0 (the whole window) or >= 10");
  nonNegative(velocimeter.aided_vel_random_walk, "velocimeter.aided_vel_random_walk");
  nonNegative(gravity.velocity_error_correlation_time, "gravity.velocity_error_correlation_time");
  positive(gravity.accel_sigma, "gravity.accel_sigma");
  positive(gravity.accel_bias_bound, "gravity.accel_bias_bound");
  positive(gravity.accel_bias_prior_sigma, "gravity.accel_bias_prior_sigma");
  nonNegative(gravity.lowpass_cutoff_hz, "gravity.lowpass_cutoff_hz");  // 0: no filter
  positive(gravity.loss_scale, "gravity.loss_scale");
  require(gravity.max_iterations >= 1, "gravity.max_iterations", "must be >= 1");
  require(gravity.use_body_equation || gravity.use_lidar_equation, "gravity.use_body_equation",
          "at least one of the body and LiDAR equations must be used");
  const Mat3& R = extrinsics.R_bl;
  require(R.allFinite() && (R.transpose() * R - Mat3::Identity()).norm() < 1e-6 &&
              R.determinant() > 0,
          "extrinsics.R_bl", "is not a rotation matrix");
  require(extrinsics.p_bl.allFinite(), "extrinsics.p_bl", "must be finite");
}

const char* toString(InitStatus s) {
  switch (s) {
    case InitStatus::Ok: return "ok";
    case InitStatus::NotEnoughData: return "not_enough_data";
    case InitStatus::NoDoppler: return "no_doppler";
    case InitStatus::DegenerateGeometry: return "degenerate_geometry";
    case InitStatus::SolverFailed: return "solver_failed";
    case InitStatus::AmbiguousMotion: return "ambiguous_motion";
    case InitStatus::InconsistentData: return "inconsistent_data";
  }
  return "unknown";
}

}  // namespace freeinit
