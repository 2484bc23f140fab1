// INI loading and echo of AppConfig. One table of keys (visitConfig) drives both loading and
// dumping, so the documented INI and the loader cannot drift apart.
#include <freeinit/mrpt/IniLoader.h>
#include <freeinit/mrpt/app_config.h>
#include <mrpt/config/CConfigFile.h>
#include <mrpt/config/CConfigFileMemory.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace freeinit::mrpt_glue {
namespace {

// Calls v(section, key, value&, unit, doc) for every scalar key of the configuration.
template <class Visitor>
void visitConfig(Visitor& v, AppConfig& c) {
  auto& est = c.core.estimator;
  v("estimator", "method", est.method, "-",
    "joint (one filter and smoother over the window) | paper (velocimeter, then gravity solve)");
  v("estimator", "bootstrap_duration", est.bootstrap_duration, "s",
    "span of the start decision (what moves)");
  v("estimator", "bootstrap_points", est.bootstrap_points, "-",
    "returns of that span used, at most (evenly spread)");
  v("estimator", "initial_tilt_sigma", est.initial_tilt_sigma, "rad",
    "std of roll and pitch at the window start (large: the tilt comes from the data)");
  v("estimator", "max_iterations", est.max_iterations, "-", "smoother iterations, at most");
  v("estimator", "zero_rate_at_rest", est.zero_rate_at_rest, "bool",
    "while the IMU shows rest the gyro measures its bias");
  v("estimator", "rest_velocity_sigma", est.rest_velocity_sigma, "m/s",
    "std of the zero body velocity while the IMU shows rest");
  v("estimator", "accel_bias_random_walk", est.accel_bias_random_walk, "m/s^2/sqrt(s)",
    "accelerometer bias random walk");

  auto& vel = c.core.velocimeter;
  v("velocimeter", "doppler_sigma", vel.doppler_sigma, "m/s", "Doppler noise std");
  v("velocimeter", "gyro_sigma", vel.gyro_sigma, "rad/s", "gyro white noise per sample");
  v("velocimeter", "vel_random_walk", vel.vel_random_walk, "m/s^2/sqrt(Hz)",
    "random walk density of the LiDAR and body velocities");
  v("velocimeter", "omega_random_walk", vel.omega_random_walk, "rad/s^2/sqrt(Hz)",
    "random walk density of the angular velocity");
  v("velocimeter", "aided_vel_random_walk", vel.aided_vel_random_walk, "m/s^2/sqrt(Hz)",
    "velocity random walk density in the accelerometer-aided refinement passes");
  v("velocimeter", "gyro_bias_random_walk", vel.gyro_bias_random_walk, "rad/s/sqrt(s)",
    "Gauss-Markov gyro bias driving noise");
  v("velocimeter", "gyro_bias_tau", vel.gyro_bias_tau, "s", "Gauss-Markov correlation time");
  v("velocimeter", "gyro_bias_sigma0", vel.gyro_bias_sigma0, "rad/s", "initial gyro bias std");
  v("velocimeter", "gyro_bias_prior", vel.gyro_bias_prior, "rad/s",
    "initial gyro bias x y z (e.g. from a static calibration)");
  v("velocimeter", "kinematic_propagation", vel.kinematic_propagation, "bool",
    "add -omega x v and the gyro slope to the propagation");
  v("velocimeter", "doppler_updates_omega", vel.doppler_updates_omega, "bool",
    "Doppler also updates omega and b_g through the lever arm (off: consider states)");
  v("velocimeter", "min_range", vel.min_range, "m", "closer points are skipped");
  v("velocimeter", "max_range", vel.max_range, "m", "farther points are skipped");
  v("velocimeter", "point_stride", vel.point_stride, "-",
    "use one point in N (1: every point; 0: automatic from max_point_rate)");
  v("velocimeter", "max_point_rate", vel.max_point_rate, "points/s",
    "automatic stride: the one that brings the points used closest to this rate");
  v("velocimeter", "gate_sigma", vel.gate_sigma, "sigma",
    "reject a point when |residual| > gate_sigma * sqrt(S) ...");
  v("velocimeter", "gate_min", vel.gate_min, "m/s", "... but never below this ...");
  v("velocimeter", "gate_rel", vel.gate_rel, "-", "... plus this fraction of the LiDAR speed");
  v("velocimeter", "doppler_ego_compensated", vel.doppler_ego_compensated, "bool",
    "the input Doppler already has the ego motion removed (some Aeva drivers)");

  auto& bs = c.core.bootstrap;
  v("bootstrap", "points", bs.points, "-", "first points used by the robust start");
  v("bootstrap", "iterations", bs.iterations, "-", "IRLS iterations");
  v("bootstrap", "cauchy_scale", bs.cauchy_scale, "m/s", "IRLS Cauchy scale");
  v("bootstrap", "prior_sigma", bs.prior_sigma, "m/s", "weak prior on each velocity axis");
  v("bootstrap", "min_info_eigen", bs.min_info_eigen, "1/(m/s)^2",
    "smallest information eigenvalue accepted (else degenerate geometry)");

  auto& st = c.core.static_detector;
  v("static_detector", "enabled", st.enabled, "bool", "detect a static start (ZUPT mode)");
  v("static_detector", "max_speed", st.max_speed, "m/s", "LiDAR speed below which at rest");
  v("static_detector", "max_gyro_dev", st.max_gyro_dev, "rad/s",
    "gyro deviation from its mean at rest");
  v("static_detector", "zupt_sigma", st.zupt_sigma, "m/s", "zero-velocity pseudo-measurement std");
  v("static_detector", "check_period", st.check_period, "s", "how often motion is checked");

  v("window", "imu_samples", c.core.window.imu_samples, "-",
    "window length in IMU samples (paper: ~100)");
  v("window", "refinement_passes", c.core.window.refinement_passes, "-",
    "accelerometer-aided passes after the paper's (0: the paper's single pass)");
  v("window", "seed_pass_stride", c.core.window.seed_pass_stride, "-",
    "extra decimation of the passes that only seed a refinement");
  v("window", "seed_imu_samples", c.core.window.seed_imu_samples, "-",
    "length of the seed passes (0: the whole window; 60 = 0.3 s at 200 Hz); shorter: lower online latency");

  auto& g = c.core.gravity;
  v("gravity", "formulation", g.formulation, "-", "integrated | differentiated");
  v("gravity", "use_body_equation", g.use_body_equation, "bool", "body kinematics residuals");
  v("gravity", "use_lidar_equation", g.use_lidar_equation, "bool",
    "LiDAR kinematics residuals (lever-arm terms)");
  v("gravity", "accel_sigma", g.accel_sigma, "m/s^2", "accelerometer white noise per sample");
  v("gravity", "accel_bias_bound", g.accel_bias_bound, "m/s^2", "|b_a| bound per axis");
  v("gravity", "accel_bias_prior_sigma", g.accel_bias_prior_sigma, "m/s^2",
    "weak zero-mean prior on b_a");
  v("gravity", "lowpass_cutoff_hz", g.lowpass_cutoff_hz, "Hz",
    "low-pass cutoff of the differentiated formulation");
  v("gravity", "velocity_error_correlation_time", g.velocity_error_correlation_time, "s",
    "correlation time of the velocimeter's velocity error (0: white)");
  v("gravity", "equations_share_errors", g.equations_share_errors, "bool",
    "body and LiDAR velocities come from the same points: halve each equation's weight");
  v("gravity", "estimate_gyro_bias", g.estimate_gyro_bias, "bool",
    "estimate a gyro-bias correction with the integrated formulation");
  v("gravity", "loss_scale", g.loss_scale, "sigma", "Cauchy loss scale on whitened residuals");
  v("gravity", "max_iterations", g.max_iterations, "-", "Ceres iterations");

  v("input", "imu_label", c.input.imu_label, "-",
    "sensorLabel of the IMU observations (empty: any)");
  v("input", "lidar_label", c.input.lidar_label, "-",
    "sensorLabel of the point-cloud observations (empty: any)");
  v("input", "imu_accel_in_g", c.input.imu_accel_in_g, "bool",
    "accelerometer given in g (converted with 9.81); otherwise m/s^2");
  v("input", "min_imu_rate", c.input.min_imu_rate, "Hz", "slower IMU streams are rejected");
  v("input", "drop_invalid_points", c.input.drop_invalid_points, "bool",
    "drop NaN/inf points (reported) instead of failing");

  auto& o = c.output;
  v("output", "simplemap", o.simplemap, "bool", "static_map.simplemap (stock MRPT classes)");
  v("output", "ply", o.ply, "bool", "static_map.ply");
  v("output", "trajectory", o.trajectory, "bool", "trajectory_tum.txt");
  v("output", "velocities", o.velocities, "bool", "velocimeter.csv");
  v("output", "snapshots", o.snapshots, "bool", "PNG snapshots rendered offscreen");
  v("output", "snapshot_width", o.snapshot_width, "px", "snapshot width");
  v("output", "snapshot_height", o.snapshot_height, "px", "snapshot height");

  // Last, so that the dump can append R_bl and p_bl to this section.
  v("extrinsics", "from_sensor_pose", c.extrinsics.from_sensor_pose, "bool",
    "take the extrinsics from the observations' sensorPose (LiDAR pose w.r.t. the IMU pose)");
}

// The loader of visitConfig: the strict IniLoader plus the app's enumerations.
class Loader : public IniLoader {
 public:
  using IniLoader::IniLoader;
  using IniLoader::operator();
  void operator()(const std::string& s, const std::string& k, GravityEstimator::Formulation& x,
                  const char*, const char*) {
    using F = GravityEstimator::Formulation;
    x = choice(s, k, {"integrated", "differentiated"}, x == F::Integrated ? 0 : 1) == 0
            ? F::Integrated
            : F::Differentiated;
  }
  void operator()(const std::string& s, const std::string& k, EstimatorParams::Method& x,
                  const char*, const char*) {
    using M = EstimatorParams::Method;
    x = choice(s, k, {"joint", "paper"}, x == M::Joint ? 0 : 1) == 0 ? M::Joint : M::Paper;
  }
};

void loadExtrinsics(Loader& L, AppConfig& c) {
  const std::string s = "extrinsics";
  const bool has_R = L.has(s, "R_bl");
  const bool has_rpy = L.has(s, "roll_deg") || L.has(s, "pitch_deg") || L.has(s, "yaw_deg");
  const bool has_p = L.has(s, "p_bl");
  if (has_R && has_rpy)
    L.fail(s, "R_bl", "give either R_bl or roll_deg/pitch_deg/yaw_deg, not both");
  Mat3 R = Mat3::Identity();
  if (has_R) {
    const auto v = L.numbers(s, "R_bl", 9);
    R << v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8];
    const double orth = (R.transpose() * R - Mat3::Identity()).norm();
    const double det = R.determinant();
    if (orth > 1e-4 || std::abs(det - 1.0) > 1e-4) {
      std::ostringstream os;
      os << "not a rotation matrix (|R^T R - I| = " << orth << ", det = " << det << ")";
      L.fail(s, "R_bl", os.str());
    }
  } else if (has_rpy) {
    auto angle = [&](const char* k) {
      return L.has(s, k) ? L.numbers(s, k, 1)[0] * M_PI / 180.0 : 0.0;
    };
    // R_bl = Rz(yaw) Ry(pitch) Rx(roll), as mrpt::poses::CPose3D.
    R = (Eigen::AngleAxisd(angle("yaw_deg"), Vec3::UnitZ()) *
         Eigen::AngleAxisd(angle("pitch_deg"), Vec3::UnitY()) *
         Eigen::AngleAxisd(angle("roll_deg"), Vec3::UnitX()))
            .toRotationMatrix();
  }
  c.core.extrinsics.R_bl = R;
  if (has_p) {
    const auto v = L.numbers(s, "p_bl", 3);
    c.core.extrinsics.p_bl = Vec3(v[0], v[1], v[2]);
  }
  c.extrinsics.given_in_ini = has_R || has_rpy || has_p;
  if (c.extrinsics.given_in_ini && c.extrinsics.from_sensor_pose)
    L.fail(s, "from_sensor_pose", "true, but R_bl/p_bl/roll_deg... are given too: choose one");
  if (!c.extrinsics.given_in_ini && !c.extrinsics.from_sensor_pose)
    L.fail(s, "R_bl",
           "extrinsics missing: give R_bl (or roll_deg, pitch_deg, yaw_deg) and p_bl, or set "
           "from_sensor_pose = true");
}

AppConfig load(const mrpt::config::CConfigFileBase& cfg, const std::string& source) {
  AppConfig c;
  Loader L(cfg, source);
  visitConfig(L, c);
  loadExtrinsics(L, c);
  L.checkUnknownKeys();
  try {
    c.core.validate();
  } catch (const std::exception& e) {
    throw std::invalid_argument(source + ": " + e.what());
  }
  if (c.input.min_imu_rate <= 0) L.fail("input", "min_imu_rate", "must be > 0");
  if (c.output.snapshot_width < 64 || c.output.snapshot_height < 64)
    L.fail("output", "snapshot_width", "snapshots must be at least 64x64 px");
  return c;
}

// Wide enough for the longest key (velocity_error_correlation_time).
constexpr int kKeyWidth = 32;

class Dumper {
 public:
  explicit Dumper(std::ostream& out) : out_(out) {}
  template <class T>
  void operator()(const std::string& s, const std::string& k, T& x, const char* unit,
                  const char* doc) {
    section(s);
    std::ostringstream v;
    v << std::setprecision(10);
    write(v, x);
    out_ << std::left << std::setw(kKeyWidth) << k << "= " << std::setw(14) << v.str() << " ; ["
         << unit << "] " << doc << "\n";
  }
  void section(const std::string& s) {
    if (s == current_) return;
    out_ << (current_.empty() ? "" : "\n") << "[" << s << "]\n";
    current_ = s;
  }

 private:
  static void write(std::ostream& o, double x) { o << x; }
  static void write(std::ostream& o, int x) { o << x; }
  static void write(std::ostream& o, bool x) { o << (x ? "true" : "false"); }
  static void write(std::ostream& o, const std::string& x) { o << x; }
  static void write(std::ostream& o, const Vec3& x) { o << x.x() << " " << x.y() << " " << x.z(); }
  static void write(std::ostream& o, GravityEstimator::Formulation f) {
    o << (f == GravityEstimator::Formulation::Integrated ? "integrated" : "differentiated");
  }
  static void write(std::ostream& o, EstimatorParams::Method m) {
    o << (m == EstimatorParams::Method::Joint ? "joint" : "paper");
  }
  std::ostream& out_;
  std::string current_;
};

}  // namespace

AppConfig loadAppConfig(const std::string& ini_file) {
  if (!std::filesystem::is_regular_file(ini_file))
    throw std::invalid_argument(ini_file + ": configuration file not found");
  mrpt::config::CConfigFile cfg(ini_file);
  return load(cfg, ini_file);
}

AppConfig loadAppConfigFromText(const std::string& ini_text, const std::string& source) {
  mrpt::config::CConfigFileMemory cfg(ini_text);
  return load(cfg, source);
}

void dumpAppConfig(const AppConfig& config, std::ostream& out) {
  AppConfig c = config;  // the visitor takes non-const references
  Dumper d(out);
  visitConfig(d, c);
  if (!c.extrinsics.from_sensor_pose) {
    const Mat3& R = c.core.extrinsics.R_bl;
    const Vec3& p = c.core.extrinsics.p_bl;
    std::ostringstream r, t;
    r << std::setprecision(12);
    t << std::setprecision(12);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) r << R(i, j) << (i * 3 + j < 8 ? " " : "");
    t << p.x() << " " << p.y() << " " << p.z();
    out << std::left << std::setw(kKeyWidth) << "R_bl"
        << "= " << r.str() << " ; [-] LiDAR-to-IMU rotation, row-major\n"
        << std::setw(kKeyWidth) << "p_bl"
        << "= " << t.str() << " ; [m] LiDAR origin in the IMU frame\n";
  }
}

}  // namespace freeinit::mrpt_glue
