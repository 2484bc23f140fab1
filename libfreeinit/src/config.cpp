// The INI declarations of the estimator's parameter structs: the one place where their keys,
// units, accepted ranges and docs are written. The ranges reject values off by orders of
// magnitude (a sigma given in the wrong unit, a typo's exponent), not merely unusual ones.
#include <freeinit/config.h>
#include <freeinit/initial_state.h>
#include <freeinit/io/config_section.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <ostream>
#include <stdexcept>
#include <string>

namespace freeinit {

using config::above;
using config::aboveUpTo;
using config::atLeast;
using config::between;
using config::Checker;

// What reads each key (the readers shown in the INI):
//   joint         the joint estimator (joint/)
//   paper         the paper form (paper/)
//   odometry      the Doppler-inertial odometry after the initialization (freeinit-icp-slam)
//   input checks  the checks of a recording before it is estimated (input_checks.h, the apps)
//   baselines     the evaluation's baselines, given the window's IMU samples (report/)
// Each key that had another section or name before the sections were named by what reads them
// says so (formerly()): such INI files still load, with a notice per key.
const config::Section<EstimatorParams>& estimatorSection() {
  using P = EstimatorParams;
  using M = EstimatorParams::Method;
  static const auto s =
      config::Section<P>("estimator", "which estimator solves the window")
          .readers("joint, paper")
          .choice("method", &P::method, {{"joint", M::Joint}, {"paper", M::Paper}},
                  "joint (one filter and smoother over the window) or paper (velocimeter, then "
                  "gravity solve)");
  return s;
}

const config::Section<WindowParams>& windowSection() {
  using P = WindowParams;
  static const auto s =
      config::Section<P>("window",
                         "the initialization window, in seconds whatever the IMU rate (0.5 s = "
                         "100 samples at 200 Hz)")
          .readers("joint, paper, baselines, input checks")
          .number("duration", &P::duration, "s", between(0.05, 60),
                  "window length from its first IMU sample")
          .refused("imu_samples",
                   "no longer a key: the window is given in seconds, [window] duration (0.5 s = "
                   "100 samples at 200 Hz)")
          .refused("seed_imu_samples",
                   "no longer a key: the seed passes are given in seconds, [paper_passes] "
                   "seed_duration (0.3 s = 60 samples at 200 Hz)");
  return s;
}

const config::Section<ImuParams>& imuSection() {
  using P = ImuParams;
  static const auto s =
      config::Section<P>("imu",
                         "the IMU's noise and bias model: what is assumed of the IMU before the "
                         "window's data")
          .number("gyro_sigma", &P::gyro_sigma, "rad/s", between(1e-6, 0.5),
                  "gyro white noise per sample")
          .readBy("joint, paper, odometry")
          .formerly("velocimeter")
          .number("accel_sigma", &P::accel_sigma, "m/s^2", between(1e-5, 2),
                  "accelerometer white noise per sample")
          .readBy("joint, paper, input checks")
          .formerly("gravity")
          .vector3("gyro_bias_prior", &P::gyro_bias_prior, "rad/s", between(-1, 1),
                   "initial gyro bias x y z (e.g. from a static calibration)")
          .readBy("joint, paper, input checks")
          .formerly("velocimeter")
          .number("gyro_bias_sigma0", &P::gyro_bias_sigma0, "rad/s", between(1e-6, 1),
                  "initial gyro bias std")
          .readBy("joint, paper, input checks")
          .formerly("velocimeter")
          .number("gyro_bias_random_walk", &P::gyro_bias_random_walk, "rad/s/sqrt(s)",
                  between(0, 0.1),
                  "gyro bias driving noise (the paper form's bias is Gauss-Markov: "
                  "[paper_velocimeter] gyro_bias_tau)")
          .readBy("joint, paper, odometry")
          .formerly("velocimeter")
          .number("accel_bias_prior_sigma", &P::accel_bias_prior_sigma, "m/s^2", between(1e-4, 10),
                  "weak zero-mean prior on b_a")
          .readBy("joint, paper")
          .formerly("gravity")
          .number("accel_bias_bound", &P::accel_bias_bound, "m/s^2", aboveUpTo(0, 5),
                  "|b_a| bound per axis")
          .readBy("joint, paper, input checks")
          .formerly("gravity")
          .number("accel_bias_random_walk", &P::accel_bias_random_walk, "m/s^2/sqrt(s)",
                  between(0, 1), "accelerometer bias random walk")
          .readBy("joint")
          .formerly("estimator")
          .number("gyro_range", &P::gyro_range, "rad/s", aboveUpTo(0, 1e4),
                  "a gyro reading at or beyond this on an axis is a fault (saturation)")
          .readBy("joint")
          .number("accel_range", &P::accel_range, "m/s^2", aboveUpTo(0, 1e5),
                  "an accelerometer reading at or beyond this on an axis is a fault")
          .readBy("joint")
          .number("fault_sigmas", &P::fault_sigmas, "sigma", between(3, 1e6),
                  "a reading this many robust sigmas from the cubic through its neighbours, on "
                  "both sides, is a fault: replaced by that cubic with its noise, never integrated")
          .readBy("joint")
          .number("max_fault_share", &P::max_fault_share, "-", between(0, 1),
                  "the window declines when more of its IMU samples than this are faults")
          .readBy("joint")
          .number("max_bridged_gap", &P::max_bridged_gap, "s", between(0, 10),
                  "an IMU gap up to this is bridged (interpolated, its noise growing with the "
                  "gap); a longer one, or more missing in all, declines the window")
          .readBy("joint");
  return s;
}

const config::Section<DopplerParams>& dopplerSection() {
  using P = DopplerParams;
  static const auto s =
      config::Section<P>("doppler", "the Doppler LiDAR's noise and which of its returns are used")
          .readers("joint, paper, odometry")
          .number("doppler_sigma", &P::doppler_sigma, "m/s", between(1e-4, 1), "Doppler noise std")
          .formerly("velocimeter")
          .flag("doppler_ego_compensated", &P::doppler_ego_compensated,
                "the input Doppler already has the ego motion removed (some Aeva drivers)")
          .readBy("joint, paper")
          .formerly("velocimeter")
          .number("min_range", &P::min_range, "m", between(0, 1e3), "closer points are skipped")
          .formerly("velocimeter")
          .number("max_range", &P::max_range, "m", aboveUpTo(0, 1e4), "farther points are skipped")
          .formerly("velocimeter")
          .number("point_stride", &P::point_stride, "-", between(0, 1e6),
                  "use one point in N (1: every point; 0: automatic from max_point_rate)")
          .formerly("velocimeter")
          .number("max_point_rate", &P::max_point_rate, "points/s", between(1, 1e9),
                  "automatic stride: the one that brings the points used closest to this rate")
          .formerly("velocimeter")
          .number("gate_sigma", &P::gate_sigma, "sigma", between(1, 1e3),
                  "reject a point when |residual| > gate_sigma * sqrt(S) ...")
          .formerly("velocimeter")
          .number("gate_min", &P::gate_min, "m/s", aboveUpTo(0, 100),
                  "... but never below this ...")
          .formerly("velocimeter")
          .number("gate_rel", &P::gate_rel, "-", between(0, 1),
                  "... plus this fraction of the LiDAR speed")
          .formerly("velocimeter")
          .check([](const P& p, const Checker& c) {
            if (!(p.max_range > p.min_range))
              c.fail("max_range",
                     "must exceed min_range (" + config::formatNumber(p.min_range) + " m)");
          });
  return s;
}

const config::Section<StartParams>& startSection() {
  using P = StartParams;
  static const auto s =
      config::Section<P>("start",
                         "the start decision: what moves at the window start, and whether the "
                         "platform stands")
          .number("duration", &P::duration, "s", between(0.005, 10),
                  "span of the joint estimator's start decision (what moves)")
          .readBy("joint")
          .formerly("estimator", "bootstrap_duration")
          .number("points", &P::points, "-", between(10, 1e7),
                  "returns of that span used, at most (evenly spread)")
          .readBy("joint")
          .formerly("estimator", "bootstrap_points")
          .number("min_info_eigen", &P::min_info_eigen, "1/(m/s)^2", between(0, 1e12),
                  "smallest information eigenvalue of the start's velocity accepted (else "
                  "degenerate geometry)")
          .readBy("joint, paper")
          .formerly("bootstrap")
          .flag("detect_rest", &P::detect_rest,
                "use a start at rest (joint: zero velocity and rate while the IMU shows rest; "
                "paper: zero-velocity mode)")
          .readBy("joint, paper")
          .formerly("static_detector", "enabled")
          .number("rest_speed", &P::rest_speed, "m/s", aboveUpTo(0, 10),
                  "LiDAR speed below which the platform is at rest")
          .readBy("joint, paper")
          .formerly("static_detector", "max_speed");
  return s;
}

const config::Section<JointParams>& jointSection() {
  using P = JointParams;
  static const auto s =
      config::Section<P>("joint", "the joint filter and smoother over the window")
          .readers("joint")
          .number("initial_tilt_sigma", &P::initial_tilt_sigma, "rad", between(1e-4, 3),
                  "std of roll and pitch at the window start (large: the tilt comes from the data)")
          .formerly("estimator")
          .number("max_iterations", &P::max_iterations, "-", between(1, 100),
                  "smoother iterations, at most")
          .formerly("estimator")
          .number("node_rate", &P::node_rate, "Hz", between(0, 1e4),
                  "filter nodes at about this rate, every m-th IMU sample, all samples "
                  "integrated (0: a node per IMU sample)")
          .flag("zero_rate_at_rest", &P::zero_rate_at_rest,
                "while the IMU shows rest the gyro measures its bias")
          .formerly("estimator")
          .flag("lever_arm_gyro_noise", &P::lever_arm_gyro_noise,
                "model the gyro noise carried through the lever arm into the returns' velocity")
          .formerly("estimator")
          .number("rest_velocity_sigma", &P::rest_velocity_sigma, "m/s", between(1e-5, 1),
                  "std of the zero body velocity while the IMU shows rest")
          .formerly("estimator")
          .number("calibration_rotation_sigma_deg", &P::calibration_rotation_sigma_deg, "deg",
                  between(0, 10),
                  "accuracy of the declared LiDAR-IMU rotation, estimated where observable "
                  "(0: exact)")
          .formerly("estimator")
          .number("time_offset_sigma", &P::time_offset_sigma, "s", between(0, 0.1),
                  "accuracy of the LiDAR-IMU time offset, estimated where observable (0: exact)")
          .formerly("estimator")
          .number("test_rotation_sigma_deg", &P::test_rotation_sigma_deg, "deg", between(0, 10),
                  "calibration test: the rotation error the data are asked about (0: no test)")
          .formerly("estimator")
          .number("test_time_offset_sigma", &P::test_time_offset_sigma, "s", between(0, 0.1),
                  "calibration test: the clock offset the data are asked about (0: no test)")
          .formerly("estimator");
  return s;
}

const config::Section<PaperVelocimeterParams>& paperVelocimeterSection() {
  using P = PaperVelocimeterParams;
  static const auto s =
      config::Section<P>("paper_velocimeter",
                         "the paper form's Doppler-inertial velocimeter (paper Sec. III-B), also "
                         "the odometry's")
          .readers("paper, odometry")
          .number("vel_random_walk", &P::vel_random_walk, "m/s^2/sqrt(Hz)", between(1e-3, 1e3),
                  "random walk density of the LiDAR and body velocities")
          .formerly("velocimeter")
          .number("omega_random_walk", &P::omega_random_walk, "rad/s^2/sqrt(Hz)",
                  between(1e-4, 1e3), "random walk density of the angular velocity")
          .formerly("velocimeter")
          .number("aided_vel_random_walk", &P::aided_vel_random_walk, "m/s^2/sqrt(Hz)",
                  between(0, 1e3),
                  "velocity random walk density in the accelerometer-aided refinement passes")
          .formerly("velocimeter")
          .number("gyro_bias_tau", &P::gyro_bias_tau, "s", between(0.1, 1e9),
                  "Gauss-Markov correlation time of the gyro bias")
          .formerly("velocimeter")
          .flag("kinematic_propagation", &P::kinematic_propagation,
                "add -omega x v and the gyro slope to the propagation")
          .formerly("velocimeter")
          .flag("doppler_updates_omega", &P::doppler_updates_omega,
                "Doppler also updates omega and b_g through the lever arm (off: consider states)")
          .formerly("velocimeter");
  return s;
}

const config::Section<PaperBootstrapParams>& paperBootstrapSection() {
  using P = PaperBootstrapParams;
  static const auto s =
      config::Section<P>("paper_bootstrap",
                         "the paper form's robust start of the LiDAR velocity from the first "
                         "points (IRLS, also its motion check at rest)")
          .readers("paper")
          .number("points", &P::points, "-", between(10, 1e7),
                  "first points used by the robust start")
          .formerly("bootstrap")
          .number("iterations", &P::iterations, "-", between(0, 1000), "IRLS iterations")
          .formerly("bootstrap")
          .number("cauchy_scale", &P::cauchy_scale, "m/s", between(1e-4, 100), "IRLS Cauchy scale")
          .formerly("bootstrap")
          .number("prior_sigma", &P::prior_sigma, "m/s", between(1e-2, 1e4),
                  "weak prior on each velocity axis")
          .formerly("bootstrap");
  return s;
}

const config::Section<PaperRestParams>& paperRestSection() {
  using P = PaperRestParams;
  static const auto s =
      config::Section<P>("paper_rest",
                         "the paper form's zero-velocity mode at a start at rest ([start] "
                         "detect_rest, rest_speed)")
          .readers("paper")
          .number("max_gyro_dev", &P::max_gyro_dev, "rad/s", aboveUpTo(0, 10),
                  "gyro deviation from its mean at rest")
          .readBy("paper, input checks")
          .formerly("static_detector")
          .number("zupt_sigma", &P::zupt_sigma, "m/s", between(1e-6, 1),
                  "zero-velocity pseudo-measurement std (also [rad/s] for the gyro)")
          .formerly("static_detector")
          .number("check_period", &P::check_period, "s", between(1e-3, 10),
                  "how often motion is checked")
          .formerly("static_detector");
  return s;
}

const config::Section<PaperGravityParams>& paperGravitySection() {
  using P = PaperGravityParams;
  using F = GravityFormulation;
  static const auto s =
      config::Section<P>("paper_gravity",
                         "the paper form's accelerometer bias and gravity solve (paper Sec. III-C)")
          .readers("paper")
          .choice("formulation", &P::formulation,
                  {{"integrated", F::Integrated}, {"differentiated", F::Differentiated}},
                  "integrated (velocity differences) or differentiated (the paper's)")
          .formerly("gravity")
          .flag("use_body_equation", &P::use_body_equation, "body kinematics residuals")
          .formerly("gravity")
          .flag("use_lidar_equation", &P::use_lidar_equation,
                "LiDAR kinematics residuals (lever-arm terms)")
          .formerly("gravity")
          .number("lowpass_cutoff_hz", &P::lowpass_cutoff_hz, "Hz", between(0, 1e3),
                  "low-pass cutoff of the differentiated formulation (0: off)")
          .formerly("gravity")
          .number("velocity_error_correlation_time", &P::velocity_error_correlation_time, "s",
                  between(0, 60), "correlation time of the velocimeter's velocity error (0: white)")
          .formerly("gravity")
          .flag("equations_share_errors", &P::equations_share_errors,
                "body and LiDAR velocities come from the same points: halve each equation's weight")
          .formerly("gravity")
          .flag("estimate_gyro_bias", &P::estimate_gyro_bias,
                "estimate a gyro-bias correction with the integrated formulation")
          .formerly("gravity")
          .number("loss_scale", &P::loss_scale, "sigma", between(0.1, 1e3),
                  "Cauchy loss scale on whitened residuals")
          .formerly("gravity")
          .number("max_iterations", &P::max_iterations, "-", between(1, 1e4), "Ceres iterations")
          .formerly("gravity")
          .check([](const P& p, const Checker& c) {
            if (!p.use_body_equation && !p.use_lidar_equation)
              c.fail("use_body_equation",
                     "at least one of the body and LiDAR equations must be used");
          });
  return s;
}

const config::Section<PaperPassesParams>& paperPassesSection() {
  using P = PaperPassesParams;
  static const auto s =
      config::Section<P>("paper_passes", "the paper form's accelerometer-aided refinement passes")
          .readers("paper")
          .number("refinement_passes", &P::refinement_passes, "-", between(0, 10),
                  "accelerometer-aided passes after the paper's (0: the paper's single pass)")
          .formerly("window")
          .number("seed_pass_stride", &P::seed_pass_stride, "-", between(1, 1000),
                  "extra decimation of the passes that only seed a refinement")
          .formerly("window")
          .number("seed_duration", &P::seed_duration, "s", between(0, 60),
                  "length of the seed passes (0: the whole window); shorter: lower online latency")
          .formerly("window")
          .check([](const P& p, const Checker& c) {
            if (p.seed_duration != 0 && p.seed_duration < 0.05)
              c.fail("seed_duration", "must be 0 (the whole window) or >= 0.05 s");
          });
  return s;
}

void FreeInitConfig::validate() const {
  estimatorSection().validate(estimator);
  windowSection().validate(window);
  imuSection().validate(imu);
  dopplerSection().validate(doppler);
  startSection().validate(start);
  jointSection().validate(joint);
  paperVelocimeterSection().validate(paper_velocimeter);
  paperBootstrapSection().validate(paper_bootstrap);
  paperRestSection().validate(paper_rest);
  paperGravitySection().validate(paper_gravity);
  paperPassesSection().validate(paper_passes);
  const Mat3& R = extrinsics.R_bl;
  if (!(R.allFinite() && (R.transpose() * R - Mat3::Identity()).norm() < 1e-6 &&
        R.determinant() > 0))
    throw config::ConfigError("configuration key extrinsics.R_bl: is not a rotation matrix");
  if (!extrinsics.p_bl.allFinite())
    throw config::ConfigError("configuration key extrinsics.p_bl: must be finite");
}

void FreeInitConfig::load(const config::IniFile& file, std::vector<std::string>* notices) {
  std::vector<std::string> renamed;
  const config::IniFile ini = config::renameFormerKeys(file, sections(), renamed);
  if (notices)
    notices->insert(notices->end(), renamed.begin(), renamed.end());
  else
    for (const std::string& n : renamed) std::cerr << n << "\n";
  estimatorSection().load(ini, estimator);
  windowSection().load(ini, window);
  imuSection().load(ini, imu);
  dopplerSection().load(ini, doppler);
  startSection().load(ini, start);
  jointSection().load(ini, joint);
  paperVelocimeterSection().load(ini, paper_velocimeter);
  paperBootstrapSection().load(ini, paper_bootstrap);
  paperRestSection().load(ini, paper_rest);
  paperGravitySection().load(ini, paper_gravity);
  paperPassesSection().load(ini, paper_passes);
}

void FreeInitConfig::dump(std::ostream& out) const {
  estimatorSection().dump(estimator, out);
  out << "\n";
  windowSection().dump(window, out);
  out << "\n";
  imuSection().dump(imu, out);
  out << "\n";
  dopplerSection().dump(doppler, out);
  out << "\n";
  startSection().dump(start, out);
  out << "\n";
  jointSection().dump(joint, out);
  out << "\n";
  paperVelocimeterSection().dump(paper_velocimeter, out);
  out << "\n";
  paperBootstrapSection().dump(paper_bootstrap, out);
  out << "\n";
  paperRestSection().dump(paper_rest, out);
  out << "\n";
  paperGravitySection().dump(paper_gravity, out);
  out << "\n";
  paperPassesSection().dump(paper_passes, out);
}

std::vector<const config::SectionBase*> FreeInitConfig::sections() {
  return {&estimatorSection(),        &windowSection(),         &imuSection(),
          &dopplerSection(),          &startSection(),          &jointSection(),
          &paperVelocimeterSection(), &paperBootstrapSection(), &paperRestSection(),
          &paperGravitySection(),     &paperPassesSection()};
}

std::vector<std::string> FreeInitConfig::sectionNames() {
  std::vector<std::string> names;
  for (const config::SectionBase* s : sections()) names.push_back(s->name());
  return names;
}

std::vector<std::string> FreeInitConfig::formerSectionNames() {
  return config::formerSectionNames(sections());
}

WindowSample windowSample(double t_first, double t_prev, double t, double duration) {
  if (!(t > t_prev)) return WindowSample::Inside;  // the first sample
  const double dt = t - t_prev;
  const double end = duration - 0.01 * dt;
  if (t - t_first >= end) return WindowSample::Outside;
  if (t - t_first + dt >= end) return WindowSample::Last;
  return WindowSample::Inside;
}

WindowSample windowSampleAt(double t_first, double t, double interval, double duration) {
  if (!(t > t_first)) return WindowSample::Inside;  // the first sample
  const double end = duration - 0.01 * interval;
  if (t - t_first >= end) return WindowSample::Outside;
  if (t - t_first + interval >= end) return WindowSample::Last;
  return WindowSample::Inside;
}

double nominalInterval(const std::vector<ImuSample>& imu, std::size_t first) {
  constexpr std::size_t kIntervals = 20;
  if (first + 1 >= imu.size()) return 0.0;
  const std::size_t n = std::min(kIntervals, imu.size() - 1 - first);
  std::vector<double> dt(n);
  for (std::size_t i = 0; i < n; ++i) dt[i] = imu[first + i + 1].t - imu[first + i].t;
  std::nth_element(dt.begin(), dt.begin() + static_cast<std::ptrdiff_t>(n / 2), dt.end());
  return dt[n / 2];
}

std::optional<std::size_t> windowLastSample(const std::vector<ImuSample>& imu, std::size_t first,
                                            double duration) {
  const double h = nominalInterval(imu, first);
  for (std::size_t k = first + 1; k < imu.size(); ++k) {
    switch (windowSampleAt(imu[first].t, imu[k].t, h, duration)) {
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
