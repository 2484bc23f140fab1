// Presets mirroring Table I of the Free-Init paper plus tunnel variants. A preset fills the whole
// ScenarioConfig from its name: the scene, the motion and the nominal extrinsics; noise, biases
// (random_biases), the extrinsic perturbation (+-0.5 deg, +-1 cm) and the object placement depend
// on the seed.
//
// | name             | platform  | scene    | motion                                          |
// |------------------|-----------|----------|-------------------------------------------------|
// | dyna_01          | handheld  | street   | rotational, ~5 rad/s peak, walking 1.0 m/s      |
// | dyna_02          | handheld  | corridor | rotational, ~5 rad/s peak, walking 1.0 m/s      |
// | dyna_03          | handheld  | street   | translational, running 5 m/s                    |
// | dyna_04          | handheld  | street   | rotational, ~10 rad/s peak, walking 1.0 m/s     |
// | dyna_05          | vehicular | street   | 75 km/h (20.83 m/s) in lane y = -2.5            |
// | dyna_06          | vehicular | street   | 60 km/h (16.67 m/s) in lane y = -2.5            |
// | stat_01          | handheld  | corridor | still 1.5 s, then walking 1.2 m/s               |
// | stat_02          | wheeled   | street   | still 2.0 s, then 1.5 m/s on the sidewalk       |
// | stat_03          | wheeled   | open     | still 1.0 s, then 2.0 m/s                       |
// | stat_04          | handheld  | street   | still 1.2 s, then walking 1.4 m/s               |
// | tunnel_handheld  | handheld  | tunnel   | walking 1.4 m/s, 4 m x 3 m tunnel               |
// | tunnel_wheeled   | wheeled   | tunnel   | 6.5 m/s, 7 m x 5 m tunnel                       |
// | tunnel_vehicular | vehicular | tunnel   | 17 m/s, 10 m x 6.5 m tunnel                     |
#pragma once

#include <freeinit/sim/analytic_trajectory.h>
#include <freeinit/sim/scene.h>
#include <freeinit/sim/simulator.h>

#include <memory>
#include <string>

namespace freeinit::sim {

/// Human-readable description of a preset.
struct PresetInfo {
  std::string name;
  std::string platform;           ///< "handheld", "wheeled" or "vehicular"
  std::string scene;              ///< "street", "corridor", "tunnel" or "open"
  std::string motion;             ///< "rotational", "translational" or "stationary"
  double nominal_speed = 0;       ///< [m/s] cruise speed once moving
  double nominal_peak_omega = 0;  ///< [rad/s] design peak |omega_b| in the first 0.5 s (0: mild)
  double still_duration = 0;      ///< [s] exact standstill at the start (stat presets)
};

/// Description of a preset; throws std::invalid_argument on an unknown name.
PresetInfo presetInfo(const std::string& name);

/// The body trajectory of a config (as makeTrajectory; kept for the callers of the presets).
inline std::shared_ptr<const AnalyticTrajectory> makePresetTrajectory(
    const ScenarioConfig& config) {
  return makeTrajectory(config);
}

/// The scene of a config (as makeScene): for a preset, sized so that the platform stays inside it
/// for config.duration.
inline std::shared_ptr<const Scene> makePresetScene(const ScenarioConfig& config,
                                                    const Trajectory& trajectory) {
  return makeScene(config, trajectory);
}

/// The true LiDAR-IMU extrinsics of a config (as makeExtrinsics). Presets: R_bl = Rz(5 deg)
/// Ry(-3 deg) Rx(2 deg) and p_bl = (0.08, -0.05, 0.12) m, each perturbed per seed (up to +-0.5 deg
/// per angle, +-1 cm per axis).
inline Extrinsics makePresetExtrinsics(const ScenarioConfig& config) {
  return makeExtrinsics(config);
}

}  // namespace freeinit::sim
