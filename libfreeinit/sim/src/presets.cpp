#include <freeinit/sim/presets.h>
#include <freeinit/sim/scene_builders.h>

#include "random_stream.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

namespace freeinit::sim {
namespace {

constexpr double kDeg = M_PI / 180.0;

const std::vector<PresetInfo>& table() {
  // A function-local constant table (immutable, no mutable static state).
  static const std::vector<PresetInfo> kTable = {
      {"dyna_01", "handheld", "street", "rotational", 1.0, 5.0, 0},
      {"dyna_02", "handheld", "corridor", "rotational", 1.0, 5.0, 0},
      {"dyna_03", "handheld", "street", "translational", 5.0, 0, 0},
      {"dyna_04", "handheld", "street", "rotational", 1.0, 10.0, 0},
      {"dyna_05", "vehicular", "street", "translational", 75.0 / 3.6, 0, 0},
      {"dyna_06", "vehicular", "street", "translational", 60.0 / 3.6, 0, 0},
      {"stat_01", "handheld", "corridor", "stationary", 1.2, 0, 1.5},
      {"stat_02", "wheeled", "street", "stationary", 1.5, 0, 2.0},
      {"stat_03", "wheeled", "open", "stationary", 2.0, 0, 1.0},
      {"stat_04", "handheld", "street", "stationary", 1.4, 0, 1.2},
      {"tunnel_handheld", "handheld", "tunnel", "translational", 1.4, 0, 0},
      {"tunnel_wheeled", "wheeled", "tunnel", "translational", 6.5, 0, 0},
      {"tunnel_vehicular", "vehicular", "tunnel", "translational", 17.0, 0, 0},
  };
  return kTable;
}

Sinusoid wave(double amplitude, double freq_hz, double phase = 0) {
  return Sinusoid{amplitude, freq_hz, phase};
}

/// A sinusoid of amplitude A whose rate peaks (positively) at tau_peak.
Sinusoid rateWave(double amplitude, double freq_hz, double tau_peak) {
  return Sinusoid{amplitude, freq_hz, -2.0 * M_PI * freq_hz * tau_peak};
}

/// Walking with hand shake: bobbing, swaying and small attitude jitter.
void addHandheldWalk(TrajectoryParams& p, double speed) {
  p.pos[0].poly = {0.0, speed};
  p.pos[0].waves = {wave(0.015, 1.8, 0.3)};
  p.pos[1].waves = {wave(0.05, 0.9, 1.1), wave(0.01, 2.9)};
  p.pos[2].waves = {wave(0.025, 1.8, 1.0), wave(0.01, 3.1, 0.2)};
  p.rpy[0].waves = {wave(0.03, 0.9, 0.4), wave(0.01, 2.7)};
  p.rpy[1].waves = {wave(0.025, 1.8, 2.0), wave(0.008, 3.3)};
  p.rpy[2].waves = {wave(0.04, 0.45, 0.7), wave(0.01, 2.3, 1.3)};
}

void addWheeled(TrajectoryParams& p, double speed) {
  p.pos[0].poly = {0.0, speed};
  p.pos[1].waves = {wave(0.08, 0.25, 0.5)};
  p.pos[2].waves = {wave(0.004, 6.0), wave(0.002, 11.0, 0.3)};
  p.rpy[0].waves = {wave(0.01, 1.1, 0.2), wave(0.003, 5.3)};
  p.rpy[1].waves = {wave(0.012, 1.7, 0.9), wave(0.003, 6.1)};
  p.rpy[2].waves = {wave(0.03, 0.25, 2.0)};
}

void addVehicle(TrajectoryParams& p, double speed) {
  // Cruise speed at tau = 0 exactly (the speed wave has zero rate there), slight acceleration.
  p.pos[0].poly = {0.0, speed, 0.1};
  p.pos[0].waves = {wave(0.3, 0.2, 0.5 * M_PI)};
  p.pos[1].waves = {wave(0.15, 0.15, 0.3)};
  p.pos[2].waves = {wave(0.015, 1.3), wave(0.005, 4.0, 1.0)};
  p.rpy[0].waves = {wave(0.012, 0.9, 0.5), wave(0.004, 3.1)};
  p.rpy[1].waves = {wave(0.01, 1.3, 1.2), wave(0.003, 4.2)};
  p.rpy[2].waves = {wave(0.015, 0.15, 0.3 + 0.5 * M_PI)};
}

/// Large rotational excitation whose component rates peak inside the first 0.5 s.
void addRotation(TrajectoryParams& p, double yaw_amp, double yaw_hz, double roll_amp,
                 double roll_hz, double pitch_amp, double pitch_hz) {
  p.rpy[2].waves.push_back(rateWave(yaw_amp, yaw_hz, 0.15));
  p.rpy[0].waves.push_back(rateWave(roll_amp, roll_hz, 0.18));
  p.rpy[1].waves.push_back(rateWave(pitch_amp, pitch_hz, 0.12));
}

}  // namespace

std::vector<std::string> presetNames() {
  std::vector<std::string> names;
  for (const PresetInfo& i : table()) names.push_back(i.name);
  return names;
}

PresetInfo presetInfo(const std::string& name) {
  for (const PresetInfo& i : table()) {
    if (i.name == name) return i;
  }
  throw std::invalid_argument("freeinit::sim: unknown preset '" + name + "'");
}

ScenarioConfig preset(const std::string& name, std::uint64_t seed) {
  presetInfo(name);  // validates the name
  ScenarioConfig c;
  c.name = name;
  c.seed = seed;
  return c;
}

std::shared_ptr<const AnalyticTrajectory> makePresetTrajectory(const ScenarioConfig& config) {
  const PresetInfo info = presetInfo(config.name);
  const std::string& n = config.name;
  TrajectoryParams p;
  p.t0 = config.t0;
  // Start attitude: a few degrees of roll and pitch, heading along the street (+x).
  p.rpy_start = Vec3(3.0 * kDeg, -4.0 * kDeg, 2.0 * kDeg);
  if (info.platform == "handheld") {
    // Street: right sidewalk; corridor / tunnel: near the centre.
    p.p_start_w = Vec3(0, info.scene == "street" ? -8.2 : (info.scene == "tunnel" ? -0.6 : 0.0),
                       1.4);
    addHandheldWalk(p, info.nominal_speed);
  } else if (info.platform == "wheeled") {
    p.p_start_w = Vec3(0, info.scene == "street" ? -8.2 : (info.scene == "tunnel" ? -1.5 : 0.0),
                       0.6);
    p.rpy_start = Vec3(2.0 * kDeg, 3.0 * kDeg, -1.5 * kDeg);
    addWheeled(p, info.nominal_speed);
  } else {
    p.p_start_w = Vec3(0, info.scene == "tunnel" ? -2.0 : -2.5, 1.9);
    p.rpy_start = Vec3(-2.0 * kDeg, 3.5 * kDeg, 0.5 * kDeg);
    addVehicle(p, info.nominal_speed);
  }
  if (n == "dyna_01") addRotation(p, 0.45, 1.6, 0.15, 2.0, 0.10, 1.4);
  if (n == "dyna_02") addRotation(p, 0.40, 1.8, 0.12, 2.2, 0.18, 1.6);
  if (n == "dyna_04") addRotation(p, 0.75, 2.0, 0.28, 2.5, 0.20, 1.8);
  if (n == "dyna_03") {
    // Running: stronger bobbing and sway at the step frequency.
    p.pos[2].waves = {wave(0.05, 2.8, 0.4), wave(0.015, 5.6)};
    p.pos[1].waves = {wave(0.06, 1.4, 1.0)};
    p.rpy[0].waves = {wave(0.04, 1.4, 0.2), wave(0.01, 4.1)};
    p.rpy[1].waves = {wave(0.04, 2.8, 1.7), wave(0.01, 5.3)};
  }
  if (info.still_duration > 0) {
    p.still_until = info.still_duration;
    p.blend_duration = 1.0;
  }
  return std::make_shared<AnalyticTrajectory>(std::move(p));
}

std::shared_ptr<const Scene> makePresetScene(const ScenarioConfig& config,
                                             const Trajectory& trajectory) {
  const PresetInfo info = presetInfo(config.name);
  double x_min = 1e300, x_max = -1e300;
  const int n = std::max(2, static_cast<int>(std::ceil(config.duration * 20.0)) + 1);
  for (int i = 0; i < n; ++i) {
    const double x = trajectory.at(config.t0 + config.duration * i / (n - 1)).p_w.x();
    x_min = std::min(x_min, x);
    x_max = std::max(x_max, x);
  }
  std::mt19937_64 rng = detail::randomStream(config.seed, detail::Stream::Scene);
  if (info.scene == "street") {
    StreetOptions o;
    o.x_min = x_min;
    o.x_max = x_max;
    o.duration = config.duration;
    if (info.platform == "vehicular") {
      o.ego_lane_speed = info.nominal_speed;
      o.cars_per_100m = config.name == "dyna_06" ? 7.0 : 5.0;
      o.pedestrians_per_100m = 3.0;
    }
    return std::make_shared<Scene>(makeStreetScene(o, rng));
  }
  if (info.scene == "corridor") {
    CorridorOptions o;
    o.x_min = x_min;
    o.x_max = x_max;
    o.pedestrians = config.name == "dyna_02" ? 2 : 1;
    return std::make_shared<Scene>(makeCorridorScene(o, rng));
  }
  if (info.scene == "tunnel") {
    TunnelOptions o;
    o.x_min = x_min;
    o.x_max = x_max;
    if (info.platform == "handheld") {
      o.half_width = 2.0;
      o.height = 3.0;
    } else if (info.platform == "wheeled") {
      o.half_width = 3.5;
      o.height = 5.0;
    } else {
      o.half_width = 5.0;
      o.height = 6.5;
    }
    return std::make_shared<Scene>(makeTunnelScene(o));
  }
  OpenOptions o;
  o.x_min = x_min;
  o.x_max = x_max;
  return std::make_shared<Scene>(makeOpenScene(o, rng));
}

Extrinsics makePresetExtrinsics(const ScenarioConfig& config) {
  std::mt19937_64 rng = detail::randomStream(config.seed, detail::Stream::Extrinsics);
  std::uniform_real_distribution<double> ang(-0.5 * kDeg, 0.5 * kDeg);
  std::uniform_real_distribution<double> lev(-0.01, 0.01);
  const double roll = 2.0 * kDeg + ang(rng);
  const double pitch = -3.0 * kDeg + ang(rng);
  const double yaw = 5.0 * kDeg + ang(rng);
  Extrinsics e;
  e.R_bl = (Eigen::AngleAxisd(yaw, Vec3::UnitZ()) * Eigen::AngleAxisd(pitch, Vec3::UnitY()) *
            Eigen::AngleAxisd(roll, Vec3::UnitX()))
               .toRotationMatrix();
  e.p_bl = Vec3(0.08 + lev(rng), -0.05 + lev(rng), 0.12 + lev(rng));
  return e;
}

}  // namespace freeinit::sim
