// randomScenario(seed): the distribution documented in random_scenario.h.
#include <freeinit/sim/random_scenario.h>
#include <freeinit/sim/scene.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <random>
#include <stdexcept>
#include <string>

#include "random_stream.h"

namespace freeinit::sim {
namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr double kDuration = 3.0;  ///< [s] default recording length
constexpr double kHorizon = 6.0;   ///< [s] the scene is laid out for this much of the path
constexpr double kMaxRate = 12.0;  ///< [rad/s] handheld peak body rate, never exceeded

/// Draws of one seeded stream.
class Draw {
 public:
  Draw(std::uint64_t seed, detail::Stream stream) : rng_(detail::randomStream(seed, stream)) {}
  double u(double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng_); }
  double logU(double a, double b) { return std::exp(u(std::log(a), std::log(b))); }
  bool chance(double p) { return u(0, 1) < p; }
  int integer(int a, int b) { return std::uniform_int_distribution<int>(a, b)(rng_); }
  double sign() { return chance(0.5) ? 1.0 : -1.0; }
  double phase() { return u(0, 2.0 * M_PI); }
  /// Index i with probability w[i] / sum(w).
  std::size_t weighted(std::initializer_list<double> w) {
    double total = 0;
    for (double x : w) total += x;
    double x = u(0, total);
    std::size_t i = 0;
    for (double wi : w) {
      if (x < wi) return i;
      x -= wi;
      ++i;
    }
    return w.size() - 1;
  }
  template <typename T>
  T among(std::initializer_list<T> values) {
    return *(values.begin() + integer(0, static_cast<int>(values.size()) - 1));
  }
  Vec3 direction() {
    std::normal_distribution<double> n(0.0, 1.0);
    Vec3 v;
    do {
      v = Vec3(n(rng_), n(rng_), n(rng_));
    } while (v.norm() < 1e-6);
    return v.normalized();
  }
  /// N(0, sigma^2) truncated to |x| <= bound (by rejection).
  double truncatedNormal(double sigma, double bound) {
    std::normal_distribution<double> n(0.0, sigma);
    for (;;) {
      const double x = n(rng_);
      if (std::abs(x) <= bound) return x;
    }
  }
  Sinusoid wave(double a_lo, double a_hi, double f_lo, double f_hi) {
    const double a = u(a_lo, a_hi);
    const double f = u(f_lo, f_hi);
    return Sinusoid{a, f, phase()};
  }

 private:
  std::mt19937_64 rng_;
};

Mat3 rotationZyxDeg(const Vec3& rpy_deg) {
  const Vec3 r = rpy_deg * kDeg;
  return (Eigen::AngleAxisd(r.z(), Vec3::UnitZ()) * Eigen::AngleAxisd(r.y(), Vec3::UnitY()) *
          Eigen::AngleAxisd(r.x(), Vec3::UnitX()))
      .toRotationMatrix();
}

/// (roll, pitch, yaw) [deg] with R = Rz(yaw) Ry(pitch) Rx(roll).
Vec3 eulerZyxDeg(const Mat3& R) {
  const double pitch = std::asin(std::clamp(-R(2, 0), -1.0, 1.0));
  return Vec3(std::atan2(R(2, 1), R(2, 2)), pitch, std::atan2(R(1, 0), R(0, 0))) / kDeg;
}

struct PlatformDraw {
  PlatformClass platform = PlatformClass::Handheld;
  std::string scene, motion, start;
  double rest = 0, blend = 0, speed = 0, accel = 0;
  double tilt_deg = 0, tilt_dir = 0, yaw_offset_deg = 0, heading_deg = 0, height = 0;
};

PlatformDraw drawPlatform(std::uint64_t seed) {
  Draw d(seed, detail::Stream::DrawPlatform);
  PlatformDraw p;
  p.platform = static_cast<PlatformClass>(d.weighted({0.4, 0.3, 0.3}));
  switch (p.platform) {
    case PlatformClass::Handheld:
      p.scene = std::vector<std::string>{"street", "corridor", "parking", "open",
                                         "tunnel"}[d.weighted({0.3, 0.2, 0.2, 0.15, 0.15})];
      break;
    case PlatformClass::Wheeled:
      p.scene = std::vector<std::string>{"street", "open", "parking", "corridor",
                                         "tunnel"}[d.weighted({0.3, 0.2, 0.2, 0.15, 0.15})];
      break;
    case PlatformClass::Vehicular:
      p.scene = std::vector<std::string>{"street", "parking", "tunnel",
                                         "open"}[d.weighted({0.4, 0.25, 0.2, 0.15})];
      break;
  }
  const std::size_t start = d.weighted({0.4, 0.2, 0.4});
  p.start = std::vector<std::string>{"moving", "starting", "static"}[start];
  p.rest = start == 0 ? 0.0 : (start == 1 ? d.u(0.0, 0.6) : d.u(0.6, 2.0));
  double a_peak = 1;  // [m/s^2] peak acceleration of a start from rest
  if (p.platform == PlatformClass::Handheld) {
    const std::size_t mode = d.weighted({0.45, 0.35, 0.2});
    p.motion = std::vector<std::string>{"rotating", "walking", "running"}[mode];
    p.speed = mode == 0 ? d.u(0.0, 1.2) : (mode == 1 ? d.u(0.6, 1.8) : d.u(2.5, 5.0));
    if (p.scene == "corridor") p.speed = std::min(p.speed, 3.0);
    a_peak = d.u(1.0, 3.0);
    p.blend = mode == 0 ? d.u(0.3, 1.0) : std::max(0.3, 1.875 * p.speed / a_peak);
  } else if (p.platform == PlatformClass::Wheeled) {
    p.motion = "rolling";
    p.speed = d.u(0.3, 5.0);
    if (p.scene == "corridor") p.speed = std::min(p.speed, 2.0);
    if (p.scene == "parking") p.speed = std::min(p.speed, 3.0);
    p.accel = d.u(-0.15, 0.3);
    a_peak = d.u(0.5, 2.0);
    p.blend = std::max(0.5, 1.875 * p.speed / a_peak);
  } else {
    p.motion = "driving";
    p.speed = p.scene == "street" ? d.u(3.0, 17.0)
                                  : (p.scene == "parking" ? d.u(1.0, 5.0) : d.u(5.0, 30.0));
    p.accel = d.u(-0.5, 0.6);
    a_peak = d.u(1.0, 3.0);
    p.blend = std::max(1.0, 1.875 * p.speed / a_peak);
  }
  // Never slower than half the cruise speed within the horizon.
  p.accel = std::max(p.accel, -0.5 * p.speed / kHorizon);
  if (start == 0) p.blend = 0;
  p.heading_deg = d.u(-180.0, 180.0);
  const double max_tilt = p.platform == PlatformClass::Handheld
                              ? 30.0
                              : (p.platform == PlatformClass::Wheeled ? 12.0 : 8.0);
  p.tilt_deg = d.u(0.0, max_tilt);
  p.tilt_dir = d.phase();
  p.yaw_offset_deg = p.platform == PlatformClass::Handheld ? d.u(-40.0, 40.0) : d.u(-3.0, 3.0);
  p.height = p.platform == PlatformClass::Handheld
                 ? d.u(1.0, 1.6)
                 : (p.platform == PlatformClass::Wheeled ? d.u(0.3, 0.9) : d.u(1.2, 2.2));
  return p;
}

SceneConfig drawScene(std::uint64_t seed, const PlatformDraw& p) {
  Draw d(seed, detail::Stream::DrawScene);
  SceneConfig s;
  s.kind = p.scene;
  s.auto_extent = false;
  s.horizon = kHorizon;
  s.street.half_width = d.u(8.5, 16.0);
  s.street.cars_per_100m = d.u(0.0, 10.0);
  s.street.pedestrians_per_100m = d.u(0.0, 16.0);
  s.street.near_traffic = false;
  s.street.ego_lane_speed = p.platform == PlatformClass::Vehicular ? p.speed : 0.0;
  s.corridor.half_width = d.u(1.3, 2.5);
  s.corridor.height = d.u(2.4, 4.0);
  s.corridor.pedestrians = 0;  // people in corridors are placed as movers, clear of the platform
  const bool road_tunnel = p.platform == PlatformClass::Vehicular;
  s.tunnel.half_width = road_tunnel ? d.u(4.5, 8.0) : d.u(2.0, 6.0);
  s.tunnel.height = road_tunnel ? d.u(4.5, 7.5) : d.u(2.6, 6.0);
  s.tunnel.features_per_100m = d.chance(0.4) ? 0.0 : d.u(2.0, 20.0);
  s.open.pedestrians = d.integer(0, 6);
  s.parking.aisle_half_width = d.u(3.0, 4.5);
  s.parking.occupancy = d.u(0.3, 0.95);
  s.parking.pedestrians = d.integer(0, 4);
  s.parking.moving_cars = d.integer(0, 3);
  s.parking.duration = kHorizon;
  return s;
}

/// The platform's lateral position in the path frame for its scene.
double startLateral(const PlatformDraw& p, const SceneConfig& s, double u_pm1) {
  const bool on_foot = p.platform != PlatformClass::Vehicular;
  if (p.scene == "street") return on_foot ? -(s.street.half_width - 1.8) : -2.5;
  if (p.scene == "corridor") return 0.1 * u_pm1;
  if (p.scene == "tunnel")
    return on_foot ? -(s.tunnel.half_width - 1.0) : -0.5 * s.tunnel.half_width;
  if (p.scene == "parking") return on_foot ? u_pm1 : 0.0;
  return 0.0;
}

/// The wrist rotation of a handheld draw: its waves (axis, index) and the peak rate aimed at.
struct RotationPlan {
  std::vector<std::pair<std::size_t, std::size_t>> waves;
  double target_peak = 0;  ///< [rad/s]
};

MotionConfig drawMotion(std::uint64_t seed, const PlatformDraw& p, const SceneConfig& scene,
                        RotationPlan& rotation) {
  Draw d(seed, detail::Stream::DrawMotion);
  MotionConfig m;
  m.start_position = Vec3(0, startLateral(p, scene, d.u(-1.0, 1.0)), p.height);
  m.start_rpy_deg =
      Vec3(p.tilt_deg * std::cos(p.tilt_dir), p.tilt_deg * std::sin(p.tilt_dir), p.yaw_offset_deg);
  m.still_until = p.rest;
  m.blend_duration = p.blend;
  m.ramp_poly = true;
  m.heading_deg = p.heading_deg;
  m.pos[0].poly = {0.0, p.speed, 0.5 * p.accel};
  auto& x = m.pos[0].waves;
  auto& y = m.pos[1].waves;
  auto& z = m.pos[2].waves;
  auto& roll = m.rpy[0].waves;
  auto& pitch = m.rpy[1].waves;
  auto& yaw = m.rpy[2].waves;
  /// A heading sinusoid and the lateral motion it implies without side slip (y' = v psi):
  /// psi = A sin(w t + phi) gives y = -(v A / w) cos(w t + phi), capped at max_lateral.
  auto turn = [&](double max_amp, double max_lateral) {
    const double f = d.u(0.05, 0.3), w = 2.0 * M_PI * f, phi = d.phase();
    double a = d.u(0.0, max_amp);
    if (p.speed > 0) a = std::min(a, max_lateral * w / p.speed);
    yaw.push_back(Sinusoid{a, f, phi});
    y.push_back(Sinusoid{p.speed * a / w, f, phi - 0.5 * M_PI});
  };
  if (p.platform == PlatformClass::Handheld) {
    if (p.speed >= 0.5) {
      const bool run = p.motion == "running";
      const double fs = run ? d.u(2.6, 3.2) : d.u(1.6, 2.2);
      const double bob = run ? d.u(0.03, 0.07) : d.u(0.01, 0.035);
      z.push_back(Sinusoid{bob, fs, d.phase()});
      z.push_back(Sinusoid{bob * d.u(0.2, 0.4), 2.0 * fs, d.phase()});
      x.push_back(Sinusoid{run ? d.u(0.01, 0.03) : d.u(0.005, 0.02), fs, d.phase()});
      y.push_back(Sinusoid{d.u(0.01, 0.05), 0.5 * fs, d.phase()});
      roll.push_back(Sinusoid{d.u(0.01, 0.04), 0.5 * fs, d.phase()});
      pitch.push_back(Sinusoid{d.u(0.005, 0.03), fs, d.phase()});
      yaw.push_back(Sinusoid{d.u(0.005, 0.03), 0.5 * fs, d.phase()});
    }
    // Hand shake.
    for (auto* axis : {&roll, &pitch, &yaw})
      for (int k = 0; k < 2; ++k) axis->push_back(d.wave(0.002, 0.012, 2.0, 8.0));
    for (auto* axis : {&x, &y, &z}) axis->push_back(d.wave(0.001, 0.006, 2.0, 6.0));
    // Slow wander of where the rig points, and of the walking line.
    yaw.push_back(d.wave(0.0, 0.25, 0.05, 0.3));
    roll.push_back(d.wave(0.0, 0.08, 0.1, 0.5));
    pitch.push_back(d.wave(0.0, 0.08, 0.1, 0.5));
    y.push_back(d.wave(0.0, p.scene == "corridor" ? 0.05 : 0.15, 0.05, 0.3));
    if (p.motion == "rotating") {
      // Wrist rotations: per axis 1-2 sinusoids; drawRandomScenario() scales their rates so that
      // the peak body rate is the target.
      rotation.target_peak = d.u(1.5, kMaxRate);
      for (std::size_t axis = 0; axis < 3; ++axis) {
        const double weight = d.u(0.2, 1.0);
        const int n = d.integer(1, 2);
        for (int k = 0; k < n; ++k) {
          const double rate = weight * d.u(0.3, 1.0);  // [rad/s], rescaled later
          const double f = d.u(0.8, 3.0);
          m.rpy[axis].waves.push_back(Sinusoid{rate / (2.0 * M_PI * f), f, d.phase()});
          rotation.waves.emplace_back(axis, m.rpy[axis].waves.size() - 1);
        }
      }
    }
  } else if (p.platform == PlatformClass::Wheeled) {
    for (int k = 0; k < 2; ++k) z.push_back(d.wave(0.0005, 0.004, 4.0, 15.0));
    for (auto* axis : {&roll, &pitch}) {
      for (int k = 0; k < 2; ++k) axis->push_back(d.wave(0.0005, 0.005, 4.0, 15.0));
      axis->push_back(d.wave(0.001, 0.012, 0.5, 2.0));
    }
    turn(0.3, 0.3);
  } else {
    z.push_back(d.wave(0.003, 0.02, 1.0, 2.2));
    pitch.push_back(d.wave(0.002, 0.01, 1.0, 2.5));
    roll.push_back(d.wave(0.002, 0.01, 0.7, 2.0));
    z.push_back(d.wave(0.0005, 0.003, 8.0, 15.0));
    roll.push_back(d.wave(0.0003, 0.002, 8.0, 15.0));
    pitch.push_back(d.wave(0.0003, 0.002, 8.0, 15.0));
    x.push_back(d.wave(0.0, 0.3, 0.1, 0.3));
    turn(0.05, 0.5);
  }
  return m;
}

/// max |omega_b| over the horizon, sampled at 500 Hz (rotations are below 8 Hz: the sampled
/// maximum is within 0.2 % of the true one).
double peakRate(const AnalyticTrajectory& traj, double t0) {
  double peak = 0;
  for (int i = 0; i <= static_cast<int>(kHorizon * 500.0); ++i)
    peak = std::max(peak, traj.at(t0 + i * 2e-3).omega_b.norm());
  return peak;
}

/// Multiplies a sinusoid's rate amplitude A 2 pi f by k, widening it up to 1 rad and making it
/// faster beyond.
void scaleRate(Sinusoid& w, double k) {
  const double rate = k * w.amplitude * 2.0 * M_PI * w.freq_hz;
  w.amplitude *= k;
  if (w.amplitude > 1.0) {
    w.amplitude = 1.0;
    w.freq_hz = rate / (2.0 * M_PI);
  }
}

struct Sensors {
  int lines = 64, points = 60000;
  double frame_rate = 10, hfov = 120, vfov = 30;
  LineOrder order = LineOrder::TopDown;
  LineDirection direction = LineDirection::Alternating;
  double range_sigma = 0.02, doppler_sigma = 0.03, outliers = 0.01, min_range = 0.5,
         max_range = 150;
  double imu_rate = 200, gyro_sigma = 0.002, accel_sigma = 0.02;
  Vec3 gyro_scale = Vec3::Ones(), accel_scale = Vec3::Ones(), b_g = Vec3::Zero(),
       b_a = Vec3::Zero();
};

Sensors drawSensors(std::uint64_t seed) {
  Draw d(seed, detail::Stream::DrawSensors);
  Sensors s;
  s.order = std::vector<LineOrder>{LineOrder::TopDown, LineOrder::Interleaved,
                                   LineOrder::BottomUp}[d.weighted({0.5, 0.35, 0.15})];
  s.direction = d.chance(0.6) ? LineDirection::Alternating : LineDirection::Forward;
  s.lines = d.among({16, 32, 48, 64, 96, 128});
  s.points = static_cast<int>(std::lround(d.logU(10000.0, 120000.0)));
  s.frame_rate = d.among({10.0, 12.5, 15.0, 20.0});
  s.hfov = d.u(90.0, 125.0);
  s.vfov = d.u(20.0, 40.0);
  s.range_sigma = d.u(0.01, 0.05);
  s.doppler_sigma = d.logU(0.02, 0.05);
  s.outliers = d.u(0.0, 0.03);
  s.min_range = d.u(0.3, 0.8);
  s.max_range = d.u(150.0, 250.0);
  s.imu_rate = d.among({100.0, 150.0, 200.0, 250.0, 400.0});
  // Noise densities; per-sample sigma = density sqrt(rate) (white noise over the Nyquist band).
  s.gyro_sigma = d.logU(5e-5, 3e-4) * std::sqrt(s.imu_rate);
  s.accel_sigma = d.logU(6e-4, 3e-3) * std::sqrt(s.imu_rate);
  for (int k = 0; k < 3; ++k) s.gyro_scale[k] = d.u(0.8, 1.2);
  for (int k = 0; k < 3; ++k) s.accel_scale[k] = d.u(0.8, 1.2);
  // Within 2 sigma of the estimator's priors (gyro_bias_sigma0, accel_bias_prior_sigma).
  for (int k = 0; k < 3; ++k) s.b_g[k] = d.truncatedNormal(0.015, 0.03);
  for (int k = 0; k < 3; ++k) s.b_a[k] = d.truncatedNormal(0.1, 0.2);
  return s;
}

struct Calibration {
  Vec3 lidar_on_rig_deg = Vec3::Zero(), imu_mount_deg = Vec3::Zero(), lidar_rpy_deg = Vec3::Zero();
  Vec3 p_bl = Vec3::Zero();
  bool wrong = false;
  double time_offset = 0;
  Vec3 rotation_error_deg = Vec3::Zero(), position_error = Vec3::Zero();
};

Calibration drawCalibration(std::uint64_t seed, PlatformClass platform) {
  Draw d(seed, detail::Stream::DrawCalibration);
  Calibration c;
  const double pitch = platform == PlatformClass::Handheld ? d.u(-5.0, 5.0) : d.u(0.0, 10.0);
  c.lidar_on_rig_deg = Vec3(d.u(-3.0, 3.0), pitch, d.u(-5.0, 5.0));
  const Vec3 axis = d.direction();
  const double angle = d.u(10.0, 60.0) * kDeg;
  c.imu_mount_deg = eulerZyxDeg(Eigen::AngleAxisd(angle, axis).toRotationMatrix());
  // R_bl = R_rb^T R_rl, from the angles simulate() turns into rotations.
  const Mat3 R_bl =
      rotationZyxDeg(c.imu_mount_deg).transpose() * rotationZyxDeg(c.lidar_on_rig_deg);
  c.lidar_rpy_deg = eulerZyxDeg(R_bl);
  c.p_bl = d.direction() * d.u(0.02, 0.3);
  c.wrong = d.chance(0.25);
  if (c.wrong) {
    bool time = false, rot = false, pos = false;
    while (!time && !rot && !pos) {
      time = d.chance(0.6);
      rot = d.chance(0.6);
      pos = d.chance(0.6);
    }
    if (time) c.time_offset = d.sign() * d.u(0.001, 0.010);
    if (rot) c.rotation_error_deg = d.direction() * d.u(0.3, 2.0);
    if (pos) c.position_error = d.direction() * d.u(0.005, 0.03);
  }
  return c;
}

// ---- movers ------------------------------------------------------------------------------------

/// Distance [m] from point q to the object posed at tau (0 inside).
double distanceTo(const SceneObject& o, const Vec3& q, double tau) {
  const Vec3 c = o.center + o.velocity * tau;
  if (o.shape == ObjectShape::Cylinder) {
    const double radial = std::max(std::hypot(q.x() - c.x(), q.y() - c.y()) - o.half_size.x(), 0.0);
    const double vertical = std::max(std::abs(q.z() - c.z()) - o.half_size.z(), 0.0);
    return std::hypot(radial, vertical);
  }
  const Mat3 R = Eigen::AngleAxisd(o.yaw, Vec3::UnitZ()).toRotationMatrix();
  const Vec3 l = R.transpose() * (q - c);
  return (l.cwiseAbs() - o.half_size).cwiseMax(0.0).norm();
}

Primitive primitiveOf(const SceneObject& o) {
  const auto refl = static_cast<float>(o.reflectivity);
  if (o.shape == ObjectShape::Cylinder)
    return makeCylinder(o.center, o.half_size.x(), o.half_size.z(), refl, o.velocity);
  return makeBox(o.center, o.half_size, o.yaw, refl, o.velocity);
}

/// Places movers that are seen from the start pose and keep clear of the platform.
class MoverPlanner {
 public:
  MoverPlanner(const ScenarioConfig& c, const PlatformDraw& p)
      : c_(c),
        p_(p),
        path_(pathConfig(c)),
        traj_(makeTrajectory(path_)),
        layout_(makeScene(path_, *traj_)),
        ext_(makeExtrinsics(c)) {
    const TruthState s0 = traj_->at(c.t0);
    lidar0_ = s0.p_w + s0.R_wb * ext_.p_bl;
    Vec3 b = (s0.R_wb * ext_.R_bl).col(0);
    b.z() = 0;
    boresight_ = b.norm() > 1e-3 ? b.normalized() : Vec3::UnitX();
    normal_ = Vec3(-boresight_.y(), boresight_.x(), 0);
  }

  /// Tries up to 30 candidates; true when one was added to `objects`.
  bool place(Draw& d, std::vector<SceneObject>& objects) {
    for (int attempt = 0; attempt < 30; ++attempt) {
      SceneObject o;
      if (!candidate(d, o)) continue;
      if (visibleSamples(o) >= 2 && clear(o)) {
        objects.push_back(o);
        return true;
      }
    }
    return false;
  }

 private:
  static ScenarioConfig pathConfig(ScenarioConfig c) {
    c.motion.heading_deg = 0;
    c.scene.objects.clear();
    return c;
  }

  /// Ground point at distance D along the boresight plus l to its side.
  Vec3 ahead(double D, double l) const {
    Vec3 q = lidar0_ + D * boresight_ + l * normal_;
    q.z() = 0;
    return q;
  }

  SceneObject person(Draw& d) const {
    SceneObject o;
    o.shape = ObjectShape::Cylinder;
    o.label = "person";
    const double h = d.u(1.55, 1.95), r = d.u(0.22, 0.3);
    o.half_size = Vec3(r, r, 0.5 * h);
    o.reflectivity = d.u(0.3, 0.6);
    return o;
  }

  SceneObject vehicle(Draw& d, const char* label) const {
    SceneObject o;
    o.shape = ObjectShape::Box;
    o.label = label;
    const std::string l = label;
    if (l == "bus")
      o.half_size = Vec3(d.u(5.0, 6.25), 1.25, d.u(1.5, 1.75));
    else if (l == "truck")
      o.half_size = Vec3(d.u(4.0, 8.0), 1.25, d.u(1.6, 2.0));
    else if (l == "van")
      o.half_size = Vec3(d.u(2.4, 3.0), 1.0, d.u(1.0, 1.3));
    else if (l == "cyclist")
      o.half_size = Vec3(0.9, 0.3, 0.85);
    else
      o.half_size = Vec3(2.25, 0.9, d.u(0.7, 0.9));
    o.reflectivity = d.u(0.4, 0.95);
    return o;
  }

  /// Moves o so that it is at ground point q (its centre above it) at tau_c with velocity v.
  static void pass(SceneObject& o, const Vec3& q, const Vec3& v, double tau_c) {
    o.velocity = v;
    o.center = q + Vec3(0, 0, o.half_size.z()) - v * tau_c;
    if (o.shape == ObjectShape::Box) o.yaw = std::atan2(v.y(), v.x());
  }

  bool candidate(Draw& d, SceneObject& o) {
    const std::string& scene = c_.scene.kind;
    const bool vehicular = p_.platform == PlatformClass::Vehicular;
    const double tau_c = d.u(0.15, 0.5);
    enum Kind { Crossing, Walking, Cyclist, VehicleCrossing, LanePass };
    Kind kind = Walking;
    if (scene == "street")
      kind = std::vector<Kind>{Crossing, Walking, LanePass}[d.weighted({0.4, 0.15, 0.45})];
    else if (scene == "open")
      kind = std::vector<Kind>{Crossing, Walking, Cyclist,
                               VehicleCrossing}[d.weighted({0.35, 0.15, 0.15, 0.35})];
    else if (scene == "parking")
      kind = std::vector<Kind>{Crossing, Walking, LanePass}[d.weighted({0.4, 0.3, 0.3})];
    else if (scene == "tunnel" && (vehicular || c_.scene.tunnel.half_width >= 4.0))
      kind = d.chance(0.3) ? Walking : LanePass;
    if (kind == Crossing || kind == Walking) {
      o = person(d);
      const double speed = d.u(0.8, 1.8);
      if (kind == Crossing) {
        const double D = vehicular ? d.u(4.0, 12.0) : d.u(1.0, 5.0);
        const double dir = d.sign() * (0.5 * M_PI + d.u(-25.0, 25.0) * kDeg);
        const Vec3 v = speed * (std::cos(dir) * boresight_ + std::sin(dir) * normal_);
        pass(o, ahead(D, d.u(-0.3, 0.3) * D), v, tau_c);
      } else {
        const double D = d.u(1.5, 8.0);
        const Vec3 v = d.sign() * speed * boresight_;
        pass(o, ahead(D, d.u(-0.35, 0.35) * D), v, tau_c);
      }
      return true;
    }
    if (kind == Cyclist || kind == VehicleCrossing) {
      const char* label = kind == Cyclist ? "cyclist" : d.among({"car", "van", "bus", "truck"});
      o = vehicle(d, label);
      const double D = (vehicular ? d.u(6.0, 15.0) : d.u(3.0, 10.0)) + o.half_size.y();
      const double speed = kind == Cyclist ? d.u(3.0, 7.0) : d.u(2.0, 10.0);
      const double dir = d.sign() * (0.5 * M_PI + d.u(-20.0, 20.0) * kDeg);
      const Vec3 v = speed * (std::cos(dir) * boresight_ + std::sin(dir) * normal_);
      pass(o, ahead(D, d.u(-0.25, 0.25) * D), v, tau_c);
      return true;
    }
    // Along a lane of the path frame (x direction), through the field of view.
    const char* label = d.among({"car", "car", "van", "bus", "truck"});
    o = vehicle(d, label);
    double lane = 0, dir = d.sign();
    if (scene == "street") {
      lane = d.chance(0.5) ? -2.5 : 2.5;
      dir = lane < 0 ? 1.0 : -1.0;
    } else if (scene == "tunnel") {
      lane = vehicular ? 0.5 * c_.scene.tunnel.half_width : 0.3 * c_.scene.tunnel.half_width;
      dir = -1.0;
    } else {
      lane = d.u(-1.0, 1.0);
    }
    const double az = d.u(-0.35, 0.35) * c_.hfov_deg * kDeg;
    const Vec3 ray = std::cos(az) * boresight_ + std::sin(az) * normal_;
    if (std::abs(ray.y()) < 1e-3) return false;
    const double s = (lane - lidar0_.y()) / ray.y();
    if (!(s > 2.0 && s < 30.0)) return false;
    const double speed = d.u(3.0, 12.0);
    pass(o, Vec3(lidar0_.x() + s * ray.x(), lane, 0), Vec3(dir * speed, 0, 0), tau_c);
    return true;
  }

  /// How many of the instants 0.1, 0.2, ..., 0.6 s see some of the object: inside the field of
  /// view (with a margin) and not hidden by the scene.
  int visibleSamples(const SceneObject& o) const {
    const Primitive prim = primitiveOf(o);
    int n = 0;
    for (int i = 1; i <= 6; ++i) {
      const double tau = 0.1 * i;
      const TruthState s = traj_->at(c_.t0 + tau);
      const Mat3 R_wl = s.R_wb * ext_.R_bl;
      const Vec3 p_wl = s.p_w + s.R_wb * ext_.p_bl;
      const Vec3 c = o.center + o.velocity * tau;
      for (double dz : {0.0, 0.7, -0.7}) {
        const Vec3 q = c + Vec3(0, 0, dz * o.half_size.z());
        const Vec3 d_l = R_wl.transpose() * (q - p_wl);
        const double r = d_l.norm();
        if (r < c_.min_range + 0.3 || r > 40.0) continue;
        const double az = std::atan2(d_l.y(), d_l.x()), el = std::asin(d_l.z() / r);
        if (std::abs(az) > 0.45 * c_.hfov_deg * kDeg || std::abs(el) > 0.45 * c_.vfov_deg * kDeg)
          continue;
        const Vec3 d_w = (q - p_wl) / r;
        double s_obj = 0;
        Vec3 n_w;
        if (!prim.intersect(p_wl, d_w, tau, r + 10.0, s_obj, n_w)) continue;
        RayHit hit;
        if (layout_->castRay(p_wl, d_w, tau, s_obj, hit)) continue;  // hidden
        ++n;
        break;
      }
    }
    return n;
  }

  /// The object keeps clear of the IMU and the LiDAR over the horizon.
  bool clear(const SceneObject& o) const {
    const double clearance = p_.platform == PlatformClass::Handheld
                                 ? 0.6
                                 : (p_.platform == PlatformClass::Wheeled ? 0.8 : 1.8);
    for (int i = 0; i <= static_cast<int>(kHorizon * 20.0); ++i) {
      const double tau = 0.05 * i;
      const TruthState s = traj_->at(c_.t0 + tau);
      if (distanceTo(o, s.p_w, tau) < clearance) return false;
      if (distanceTo(o, s.p_w + s.R_wb * ext_.p_bl, tau) < clearance) return false;
    }
    return true;
  }

  const ScenarioConfig& c_;
  const PlatformDraw& p_;
  ScenarioConfig path_;
  std::shared_ptr<const AnalyticTrajectory> traj_;
  std::shared_ptr<const Scene> layout_;
  Extrinsics ext_;
  Vec3 lidar0_, boresight_, normal_;
};

}  // namespace

const char* platformName(PlatformClass platform) {
  switch (platform) {
    case PlatformClass::Handheld:
      return "handheld";
    case PlatformClass::Wheeled:
      return "wheeled";
    case PlatformClass::Vehicular:
      return "vehicular";
  }
  return "?";
}

RandomScenario drawRandomScenario(std::uint64_t seed) {
  const PlatformDraw p = drawPlatform(seed);
  ScenarioConfig c;
  c.name = "random";
  c.seed = seed;
  c.duration = kDuration;
  c.scene = drawScene(seed, p);
  RotationPlan rotation;
  c.motion = drawMotion(seed, p, c.scene, rotation);

  const Sensors s = drawSensors(seed);
  c.points_per_frame = s.points;
  c.lines = s.lines;
  c.frame_rate = s.frame_rate;
  c.hfov_deg = s.hfov;
  c.vfov_deg = s.vfov;
  c.line_order = s.order;
  c.line_direction = s.direction;
  c.min_range = s.min_range;
  c.max_range = s.max_range;
  c.range_sigma = s.range_sigma;
  c.doppler_sigma = s.doppler_sigma;
  c.outlier_ratio = s.outliers;
  c.imu_rate = s.imu_rate;
  c.gyro_sigma = s.gyro_sigma;
  c.accel_sigma = s.accel_sigma;
  c.gyro_sigma_scale = s.gyro_scale;
  c.accel_sigma_scale = s.accel_scale;
  c.random_biases = false;
  c.b_g = s.b_g;
  c.b_a = s.b_a;

  const Calibration cal = drawCalibration(seed, p.platform);
  c.motion.imu_mount_rpy_deg = cal.imu_mount_deg;
  c.lidar_rpy_deg = cal.lidar_rpy_deg;
  c.lidar_position = cal.p_bl;
  c.lidar_rpy_jitter_deg = 0;
  c.lidar_position_jitter = 0;
  c.declared_rotation_error_deg = cal.rotation_error_deg;
  c.declared_position_error = cal.position_error;
  c.lidar_time_offset = cal.time_offset;

  // The stretch the scene is laid out along: the path over the horizon.
  {
    ScenarioConfig path = c;
    path.motion.heading_deg = 0;
    const auto traj = makeTrajectory(path);
    c.scene.x_min = 1e300;
    c.scene.x_max = -1e300;
    for (int i = 0; i <= static_cast<int>(kHorizon * 20.0); ++i) {
      const double x = traj->at(c.t0 + 0.05 * i).p_w.x();
      c.scene.x_min = std::min(c.scene.x_min, x);
      c.scene.x_max = std::max(c.scene.x_max, x);
    }
    c.scene.x_max = std::max(c.scene.x_max, c.scene.x_min + 1.0);
  }

  // Handheld rotation: scale the wrist rotation until the sampled peak body rate (blend into
  // motion included) is the target, from below.
  double peak = peakRate(*makeTrajectory(c), c.t0);
  for (int iter = 0; iter < 12 && !rotation.waves.empty(); ++iter) {
    if (peak <= rotation.target_peak && peak > 0.97 * rotation.target_peak) break;
    const double k = 0.99 * rotation.target_peak / peak;
    for (const auto& [axis, i] : rotation.waves) scaleRate(c.motion.rpy[axis].waves[i], k);
    peak = peakRate(*makeTrajectory(c), c.t0);
  }
  for (int iter = 0; iter < 20 && peak > kMaxRate && !rotation.waves.empty(); ++iter) {
    for (const auto& [axis, i] : rotation.waves) scaleRate(c.motion.rpy[axis].waves[i], 0.95);
    peak = peakRate(*makeTrajectory(c), c.t0);
  }

  RandomScenario out;
  RandomScenarioInfo& info = out.info;
  info.seed = seed;
  info.platform = p.platform;
  info.scene = p.scene;
  info.motion = p.motion;
  info.start = p.start;
  info.rest_duration = p.rest;
  info.static_start = p.rest >= 0.6;
  info.speed = p.speed;
  info.peak_angular_rate = peak;

  // Movers in view.
  {
    Draw d(seed, detail::Stream::DrawMovers);
    const int wanted = info.static_start ? (d.chance(0.8) ? d.integer(1, 3) : 0)
                                         : (d.chance(0.35) ? d.integer(1, 2) : 0);
    MoverPlanner planner(c, p);
    for (int i = 0; i < wanted; ++i)
      if (planner.place(d, c.scene.objects)) ++info.movers_in_view;
  }
  info.dynamic_near_standing_sensor = info.static_start && info.movers_in_view > 0;

  const auto traj = makeTrajectory(c);
  const TruthState s0 = traj->at(c.t0);
  info.body_tilt_deg = std::acos(std::clamp(s0.R_wb(2, 2), -1.0, 1.0)) / kDeg;
  const Vec3 rpy0 = c.motion.start_rpy_deg * kDeg;
  info.base_tilt_deg =
      std::acos(std::clamp(std::cos(rpy0.x()) * std::cos(rpy0.y()), -1.0, 1.0)) / kDeg;
  const Extrinsics truth = makeExtrinsics(c);
  const Extrinsics declared = declaredExtrinsics(c, truth);
  info.calibration_wrong = cal.wrong;
  info.lidar_time_offset = c.lidar_time_offset;
  info.rotation_error_deg =
      Eigen::AngleAxisd(truth.R_bl.transpose() * declared.R_bl).angle() / kDeg;
  info.position_error = (declared.p_bl - truth.p_bl).norm();
  info.extrinsic_rotation_deg = Eigen::AngleAxisd(truth.R_bl).angle() / kDeg;
  info.lever_arm = truth.p_bl.norm();
  out.config = c;
  return out;
}

ScenarioConfig randomScenario(std::uint64_t seed) { return drawRandomScenario(seed).config; }

std::vector<std::string> describe(const RandomScenarioInfo& i) {
  char buf[512];
  std::vector<std::string> out;
  std::snprintf(buf, sizeof buf,
                "random scenario %llu: %s, %s, %s, speed %.2f m/s, peak rate %.2f rad/s within 6 s",
                static_cast<unsigned long long>(i.seed), platformName(i.platform), i.scene.c_str(),
                i.motion.c_str(), i.speed, i.peak_angular_rate);
  out.emplace_back(buf);
  std::snprintf(buf, sizeof buf,
                "start: %s (at rest %.2f s%s), base tilt %.1f deg, IMU tilt %.1f deg, %d mover(s) "
                "placed in view%s",
                i.start.c_str(), i.rest_duration, i.static_start ? ", a static start" : "",
                i.base_tilt_deg, i.body_tilt_deg, i.movers_in_view,
                i.dynamic_near_standing_sensor ? " of the standing sensor" : "");
  out.emplace_back(buf);
  std::snprintf(buf, sizeof buf,
                "calibration: R_bl %.1f deg, |p_bl| %.3f m; declared %s (time offset %.4f s, "
                "rotation off %.2f deg, position off %.4f m)",
                i.extrinsic_rotation_deg, i.lever_arm, i.calibration_wrong ? "WRONG" : "right",
                i.lidar_time_offset, i.rotation_error_deg, i.position_error);
  out.emplace_back(buf);
  if (i.moving_point_share >= 0) {
    std::snprintf(buf, sizeof buf, "points on moving objects: %.2f %% (first 0.6 s: %.2f %%)",
                  100.0 * i.moving_point_share, 100.0 * i.moving_point_share_first_0_6s);
    out.emplace_back(buf);
  }
  return out;
}

double movingPointShare(const Recording& rec, double t_begin, double t_end) {
  long n = 0, moving = 0;
  for (std::size_t f = 0; f < rec.frames.size(); ++f) {
    const LidarFrame& fr = rec.frames[f];
    for (std::size_t i = 0; i < fr.points.size(); ++i) {
      const double t = rec.pointTime(fr, fr.points[i]);
      if (t < t_begin || t > t_end) continue;
      ++n;
      if (rec.labels[f][i] == PointLabel::Dynamic) ++moving;
    }
  }
  return n > 0 ? static_cast<double>(moving) / static_cast<double>(n) : 0.0;
}

void measureMovingPoints(RandomScenarioInfo& info, const Recording& rec) {
  info.moving_point_share = movingPointShare(rec);
  info.moving_point_share_first_0_6s = movingPointShare(rec, rec.config.t0, rec.config.t0 + 0.6);
}

Misdeclaration drawMisdeclaration(std::uint64_t seed, const MisdeclarationRanges& ranges) {
  auto check = [](const DrawRange& r, bool factor, const char* name) {
    const bool ok = std::isfinite(r.lo) && std::isfinite(r.hi) && r.lo <= r.hi &&
                    (factor ? r.lo > 0 : r.lo >= 0);
    if (!ok)
      throw std::invalid_argument(std::string("freeinit::sim::drawMisdeclaration: ") + name +
                                  (factor ? ": needs 0 < lo <= hi" : ": needs 0 <= lo <= hi"));
  };
  check(ranges.imu_noise_factor, true, "imu_noise_factor");
  check(ranges.doppler_noise_factor, true, "doppler_noise_factor");
  check(ranges.time_offset, false, "time_offset");
  Draw d(seed, detail::Stream::DrawMisdeclaration);
  const double u_imu = d.u(0, 1), u_doppler = d.u(0, 1), u_offset = d.u(0, 1);
  const double sign = d.sign();
  auto logUniform = [](const DrawRange& r, double u) {
    return r.lo == r.hi ? r.lo : std::exp(std::log(r.lo) + u * (std::log(r.hi) - std::log(r.lo)));
  };
  Misdeclaration m;
  m.imu_noise_factor = logUniform(ranges.imu_noise_factor, u_imu);
  m.doppler_noise_factor = logUniform(ranges.doppler_noise_factor, u_doppler);
  const DrawRange& t = ranges.time_offset;
  const double size = t.lo == t.hi ? t.lo : t.lo + u_offset * (t.hi - t.lo);
  m.time_offset = size == 0 ? 0.0 : sign * size;
  return m;
}

}  // namespace freeinit::sim
