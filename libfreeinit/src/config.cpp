// The INI declarations of the estimator's parameter structs: the one place where their keys,
// units, accepted ranges and docs are written. The ranges reject values off by orders of
// magnitude (a sigma given in the wrong unit, a typo's exponent), not merely unusual ones.
#include <freeinit/config.h>
#include <freeinit/initial_state.h>
#include <freeinit/io/config_section.h>

#include <cmath>
#include <ostream>
#include <stdexcept>
#include <string>

namespace freeinit {

using config::above;
using config::aboveUpTo;
using config::atLeast;
using config::between;
using config::Checker;

const config::Section<EstimatorParams>& estimatorSection() {
  using P = EstimatorParams;
  using M = EstimatorParams::Method;
  static const auto s =
      config::Section<P>("estimator",
                         "which estimator solves the window, and the joint one's settings")
          .choice("method", &P::method, {{"joint", M::Joint}, {"paper", M::Paper}},
                  "joint (one filter and smoother over the window) or paper (velocimeter, then "
                  "gravity solve)")
          .number("bootstrap_duration", &P::bootstrap_duration, "s", between(0.005, 10),
                  "span of the start decision (what moves)")
          .number("bootstrap_points", &P::bootstrap_points, "-", between(10, 1e7),
                  "returns of that span used, at most (evenly spread)")
          .number("initial_tilt_sigma", &P::initial_tilt_sigma, "rad", between(1e-4, 3),
                  "std of roll and pitch at the window start (large: the tilt comes from the data)")
          .number("max_iterations", &P::max_iterations, "-", between(1, 100),
                  "smoother iterations, at most")
          .flag("zero_rate_at_rest", &P::zero_rate_at_rest,
                "while the IMU shows rest the gyro measures its bias")
          .flag("lever_arm_gyro_noise", &P::lever_arm_gyro_noise,
                "model the gyro noise carried through the lever arm into the returns' velocity")
          .number("rest_velocity_sigma", &P::rest_velocity_sigma, "m/s", between(1e-5, 1),
                  "std of the zero body velocity while the IMU shows rest")
          .number("accel_bias_random_walk", &P::accel_bias_random_walk, "m/s^2/sqrt(s)",
                  between(0, 1), "accelerometer bias random walk")
          .number("calibration_rotation_sigma_deg", &P::calibration_rotation_sigma_deg, "deg",
                  between(0, 10),
                  "accuracy of the declared LiDAR-IMU rotation, estimated where observable "
                  "(0: exact)")
          .number("time_offset_sigma", &P::time_offset_sigma, "s", between(0, 0.1),
                  "accuracy of the LiDAR-IMU time offset, estimated where observable (0: exact)")
          .number("test_rotation_sigma_deg", &P::test_rotation_sigma_deg, "deg", between(0, 10),
                  "calibration test: the rotation error the data are asked about (0: no test)")
          .number("test_time_offset_sigma", &P::test_time_offset_sigma, "s", between(0, 0.1),
                  "calibration test: the clock offset the data are asked about (0: no test)");
  return s;
}

const config::Section<VelocimeterParams>& velocimeterSection() {
  using P = VelocimeterParams;
  static const auto s =
      config::Section<P>("velocimeter", "the Doppler-inertial velocimeter (paper Sec. III-B)")
          .number("doppler_sigma", &P::doppler_sigma, "m/s", between(1e-4, 1), "Doppler noise std")
          .number("gyro_sigma", &P::gyro_sigma, "rad/s", between(1e-6, 0.5),
                  "gyro white noise per sample")
          .number("vel_random_walk", &P::vel_random_walk, "m/s^2/sqrt(Hz)", between(1e-3, 1e3),
                  "random walk density of the LiDAR and body velocities")
          .number("omega_random_walk", &P::omega_random_walk, "rad/s^2/sqrt(Hz)",
                  between(1e-4, 1e3), "random walk density of the angular velocity")
          .number("aided_vel_random_walk", &P::aided_vel_random_walk, "m/s^2/sqrt(Hz)",
                  between(0, 1e3),
                  "velocity random walk density in the accelerometer-aided refinement passes")
          .number("gyro_bias_random_walk", &P::gyro_bias_random_walk, "rad/s/sqrt(s)",
                  between(0, 0.1), "Gauss-Markov gyro bias driving noise")
          .number("gyro_bias_tau", &P::gyro_bias_tau, "s", between(0.1, 1e9),
                  "Gauss-Markov correlation time")
          .number("gyro_bias_sigma0", &P::gyro_bias_sigma0, "rad/s", between(1e-6, 1),
                  "initial gyro bias std")
          .vector3("gyro_bias_prior", &P::gyro_bias_prior, "rad/s", between(-1, 1),
                   "initial gyro bias x y z (e.g. from a static calibration)")
          .flag("kinematic_propagation", &P::kinematic_propagation,
                "add -omega x v and the gyro slope to the propagation")
          .flag("doppler_updates_omega", &P::doppler_updates_omega,
                "Doppler also updates omega and b_g through the lever arm (off: consider states)")
          .number("min_range", &P::min_range, "m", between(0, 1e3), "closer points are skipped")
          .number("max_range", &P::max_range, "m", aboveUpTo(0, 1e4), "farther points are skipped")
          .number("point_stride", &P::point_stride, "-", between(0, 1e6),
                  "use one point in N (1: every point; 0: automatic from max_point_rate)")
          .number("max_point_rate", &P::max_point_rate, "points/s", between(1, 1e9),
                  "automatic stride: the one that brings the points used closest to this rate")
          .number("gate_sigma", &P::gate_sigma, "sigma", between(1, 1e3),
                  "reject a point when |residual| > gate_sigma * sqrt(S) ...")
          .number("gate_min", &P::gate_min, "m/s", aboveUpTo(0, 100),
                  "... but never below this ...")
          .number("gate_rel", &P::gate_rel, "-", between(0, 1),
                  "... plus this fraction of the LiDAR speed")
          .flag("doppler_ego_compensated", &P::doppler_ego_compensated,
                "the input Doppler already has the ego motion removed (some Aeva drivers)")
          .check([](const P& p, const Checker& c) {
            if (!(p.max_range > p.min_range))
              c.fail("max_range",
                     "must exceed min_range (" + config::formatNumber(p.min_range) + " m)");
          });
  return s;
}

const config::Section<BootstrapParams>& bootstrapSection() {
  using P = BootstrapParams;
  static const auto s =
      config::Section<P>("bootstrap", "robust start of the LiDAR velocity from the first points")
          .number("points", &P::points, "-", between(10, 1e7),
                  "first points used by the robust start")
          .number("iterations", &P::iterations, "-", between(0, 1000), "IRLS iterations")
          .number("cauchy_scale", &P::cauchy_scale, "m/s", between(1e-4, 100), "IRLS Cauchy scale")
          .number("prior_sigma", &P::prior_sigma, "m/s", between(1e-2, 1e4),
                  "weak prior on each velocity axis")
          .number("min_info_eigen", &P::min_info_eigen, "1/(m/s)^2", between(0, 1e12),
                  "smallest information eigenvalue accepted (else degenerate geometry)");
  return s;
}

const config::Section<StaticParams>& staticDetectorSection() {
  using P = StaticParams;
  static const auto s =
      config::Section<P>("static_detector", "static-start detection and zero-velocity mode")
          .flag("enabled", &P::enabled, "detect a static start (ZUPT mode)")
          .number("max_speed", &P::max_speed, "m/s", aboveUpTo(0, 10),
                  "LiDAR speed below which at rest")
          .number("max_gyro_dev", &P::max_gyro_dev, "rad/s", aboveUpTo(0, 10),
                  "gyro deviation from its mean at rest")
          .number("zupt_sigma", &P::zupt_sigma, "m/s", between(1e-6, 1),
                  "zero-velocity pseudo-measurement std (also [rad/s] for the gyro)")
          .number("check_period", &P::check_period, "s", between(1e-3, 10),
                  "how often motion is checked");
  return s;
}

const config::Section<WindowParams>& windowSection() {
  using P = WindowParams;
  static const auto s =
      config::Section<P>("window",
                         "the initialization window, in seconds whatever the IMU rate (0.5 s = "
                         "100 samples at 200 Hz)")
          .number("duration", &P::duration, "s", between(0.05, 60),
                  "window length from its first IMU sample")
          .number("refinement_passes", &P::refinement_passes, "-", between(0, 10),
                  "accelerometer-aided passes after the paper's (0: the paper's single pass)")
          .number("seed_pass_stride", &P::seed_pass_stride, "-", between(1, 1000),
                  "extra decimation of the passes that only seed a refinement")
          .number("seed_duration", &P::seed_duration, "s", between(0, 60),
                  "length of the seed passes (0: the whole window); shorter: lower online latency")
          .refused("imu_samples",
                   "no longer a key: the window is given in seconds, [window] duration (0.5 s = "
                   "100 samples at 200 Hz)")
          .refused("seed_imu_samples",
                   "no longer a key: the seed passes are given in seconds, [window] "
                   "seed_duration (0.3 s = 60 samples at 200 Hz)")
          .check([](const P& p, const Checker& c) {
            if (p.seed_duration != 0 && p.seed_duration < 0.05)
              c.fail("seed_duration", "must be 0 (the whole window) or >= 0.05 s");
          });
  return s;
}

const config::Section<GravityParams>& gravitySection() {
  using P = GravityParams;
  using F = GravityFormulation;
  static const auto s =
      config::Section<P>("gravity", "accelerometer bias and gravity (paper Sec. III-C)")
          .choice("formulation", &P::formulation,
                  {{"integrated", F::Integrated}, {"differentiated", F::Differentiated}},
                  "integrated (velocity differences) or differentiated (the paper's)")
          .flag("use_body_equation", &P::use_body_equation, "body kinematics residuals")
          .flag("use_lidar_equation", &P::use_lidar_equation,
                "LiDAR kinematics residuals (lever-arm terms)")
          .number("accel_sigma", &P::accel_sigma, "m/s^2", between(1e-5, 2),
                  "accelerometer white noise per sample")
          .number("accel_bias_bound", &P::accel_bias_bound, "m/s^2", aboveUpTo(0, 5),
                  "|b_a| bound per axis")
          .number("accel_bias_prior_sigma", &P::accel_bias_prior_sigma, "m/s^2", between(1e-4, 10),
                  "weak zero-mean prior on b_a")
          .number("lowpass_cutoff_hz", &P::lowpass_cutoff_hz, "Hz", between(0, 1e3),
                  "low-pass cutoff of the differentiated formulation (0: off)")
          .number("velocity_error_correlation_time", &P::velocity_error_correlation_time, "s",
                  between(0, 60), "correlation time of the velocimeter's velocity error (0: white)")
          .flag("equations_share_errors", &P::equations_share_errors,
                "body and LiDAR velocities come from the same points: halve each equation's weight")
          .flag("estimate_gyro_bias", &P::estimate_gyro_bias,
                "estimate a gyro-bias correction with the integrated formulation")
          .number("loss_scale", &P::loss_scale, "sigma", between(0.1, 1e3),
                  "Cauchy loss scale on whitened residuals")
          .number("max_iterations", &P::max_iterations, "-", between(1, 1e4), "Ceres iterations")
          .check([](const P& p, const Checker& c) {
            if (!p.use_body_equation && !p.use_lidar_equation)
              c.fail("use_body_equation",
                     "at least one of the body and LiDAR equations must be used");
          });
  return s;
}

void FreeInitConfig::validate() const {
  estimatorSection().validate(estimator);
  velocimeterSection().validate(velocimeter);
  bootstrapSection().validate(bootstrap);
  staticDetectorSection().validate(static_detector);
  windowSection().validate(window);
  gravitySection().validate(gravity);
  const Mat3& R = extrinsics.R_bl;
  if (!(R.allFinite() && (R.transpose() * R - Mat3::Identity()).norm() < 1e-6 &&
        R.determinant() > 0))
    throw config::ConfigError("configuration key extrinsics.R_bl: is not a rotation matrix");
  if (!extrinsics.p_bl.allFinite())
    throw config::ConfigError("configuration key extrinsics.p_bl: must be finite");
}

void FreeInitConfig::load(const config::IniFile& ini) {
  estimatorSection().load(ini, estimator);
  velocimeterSection().load(ini, velocimeter);
  bootstrapSection().load(ini, bootstrap);
  staticDetectorSection().load(ini, static_detector);
  windowSection().load(ini, window);
  gravitySection().load(ini, gravity);
}

void FreeInitConfig::dump(std::ostream& out) const {
  estimatorSection().dump(estimator, out);
  out << "\n";
  velocimeterSection().dump(velocimeter, out);
  out << "\n";
  bootstrapSection().dump(bootstrap, out);
  out << "\n";
  staticDetectorSection().dump(static_detector, out);
  out << "\n";
  windowSection().dump(window, out);
  out << "\n";
  gravitySection().dump(gravity, out);
}

std::vector<std::string> FreeInitConfig::sectionNames() {
  return {estimatorSection().name(),      velocimeterSection().name(), bootstrapSection().name(),
          staticDetectorSection().name(), windowSection().name(),      gravitySection().name()};
}

WindowSample windowSample(double t_first, double t_prev, double t, double duration) {
  if (!(t > t_prev)) return WindowSample::Inside;  // the first sample
  const double dt = t - t_prev;
  const double end = duration - 0.01 * dt;
  if (t - t_first >= end) return WindowSample::Outside;
  if (t - t_first + dt >= end) return WindowSample::Last;
  return WindowSample::Inside;
}

std::optional<std::size_t> windowLastSample(const std::vector<ImuSample>& imu, std::size_t first,
                                            double duration) {
  for (std::size_t k = first + 1; k < imu.size(); ++k) {
    switch (windowSample(imu[first].t, imu[k - 1].t, imu[k].t, duration)) {
      case WindowSample::Outside:
        return k - 1;
      case WindowSample::Last:
        return k;
      case WindowSample::Inside:
        break;
    }
  }
  return std::nullopt;
}

const char* toString(InitStatus s) {
  switch (s) {
    case InitStatus::Ok:
      return "ok";
    case InitStatus::NotEnoughData:
      return "not_enough_data";
    case InitStatus::NoDoppler:
      return "no_doppler";
    case InitStatus::DegenerateGeometry:
      return "degenerate_geometry";
    case InitStatus::SolverFailed:
      return "solver_failed";
    case InitStatus::AmbiguousMotion:
      return "ambiguous_motion";
    case InitStatus::InconsistentData:
      return "inconsistent_data";
  }
  return "unknown";
}

}  // namespace freeinit
