#include <freeinit/sim/presets.h>

#include <cmath>
#include <stdexcept>

#include "preset_definitions.h"

namespace freeinit::sim {
namespace {

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
void addHandheldWalk(MotionConfig& p, double speed) {
  p.pos[0].poly = {0.0, speed};
  p.pos[0].waves = {wave(0.015, 1.8, 0.3)};
  p.pos[1].waves = {wave(0.05, 0.9, 1.1), wave(0.01, 2.9)};
  p.pos[2].waves = {wave(0.025, 1.8, 1.0), wave(0.01, 3.1, 0.2)};
  p.rpy[0].waves = {wave(0.03, 0.9, 0.4), wave(0.01, 2.7)};
  p.rpy[1].waves = {wave(0.025, 1.8, 2.0), wave(0.008, 3.3)};
  p.rpy[2].waves = {wave(0.04, 0.45, 0.7), wave(0.01, 2.3, 1.3)};
}

void addWheeled(MotionConfig& p, double speed) {
  p.pos[0].poly = {0.0, speed};
  p.pos[1].waves = {wave(0.08, 0.25, 0.5)};
  p.pos[2].waves = {wave(0.004, 6.0), wave(0.002, 11.0, 0.3)};
  p.rpy[0].waves = {wave(0.01, 1.1, 0.2), wave(0.003, 5.3)};
  p.rpy[1].waves = {wave(0.012, 1.7, 0.9), wave(0.003, 6.1)};
  p.rpy[2].waves = {wave(0.03, 0.25, 2.0)};
}

void addVehicle(MotionConfig& p, double speed) {
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
void addRotation(MotionConfig& p, double yaw_amp, double yaw_hz, double roll_amp, double roll_hz,
                 double pitch_amp, double pitch_hz) {
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
  detail::definePreset(name, c);
  return c;
}

namespace detail {

void definePreset(const std::string& name, ScenarioConfig& c) {
  const PresetInfo info = presetInfo(name);
  const std::string& n = name;
  // Motion: start attitude a few degrees of roll and pitch, heading along the street (+x).
  MotionConfig p;
  p.start_rpy_deg = Vec3(3.0, -4.0, 2.0);
  if (info.platform == "handheld") {
    // Street: right sidewalk; corridor / tunnel: near the centre.
    p.start_position =
        Vec3(0, info.scene == "street" ? -8.2 : (info.scene == "tunnel" ? -0.6 : 0.0), 1.4);
    addHandheldWalk(p, info.nominal_speed);
  } else if (info.platform == "wheeled") {
    p.start_position =
        Vec3(0, info.scene == "street" ? -8.2 : (info.scene == "tunnel" ? -1.5 : 0.0), 0.6);
    p.start_rpy_deg = Vec3(2.0, 3.0, -1.5);
    addWheeled(p, info.nominal_speed);
  } else {
    p.start_position = Vec3(0, info.scene == "tunnel" ? -2.0 : -2.5, 1.9);
    p.start_rpy_deg = Vec3(-2.0, 3.5, 0.5);
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
  c.motion = p;

  // Scene, sized at simulation time by the stretch the platform covers.
  SceneConfig s;
  s.kind = info.scene;
  s.auto_extent = true;
  if (info.scene == "street" && info.platform == "vehicular") {
    s.street.ego_lane_speed = info.nominal_speed;
    s.street.cars_per_100m = n == "dyna_06" ? 7.0 : 5.0;
    s.street.pedestrians_per_100m = 3.0;
  }
  s.corridor.pedestrians = n == "dyna_02" ? 2 : 1;
  if (info.platform == "handheld") {
    s.tunnel.half_width = 2.0;
    s.tunnel.height = 3.0;
  } else if (info.platform == "wheeled") {
    s.tunnel.half_width = 3.5;
    s.tunnel.height = 5.0;
  } else {
    s.tunnel.half_width = 5.0;
    s.tunnel.height = 6.5;
  }
  c.scene = s;

  // Extrinsics: R_bl = Rz(5 deg) Ry(-3 deg) Rx(2 deg), p_bl = (0.08, -0.05, 0.12) m, perturbed
  // per seed; declared exactly, on one clock.
  c.lidar_rpy_deg = Vec3(2.0, -3.0, 5.0);
  c.lidar_position = Vec3(0.08, -0.05, 0.12);
  c.lidar_rpy_jitter_deg = 0.5;
  c.lidar_position_jitter = 0.01;
  c.declared_rotation_error_deg.setZero();
  c.declared_position_error.setZero();
  c.lidar_time_offset = 0;
  c.random_biases = true;
}

}  // namespace detail

}  // namespace freeinit::sim
