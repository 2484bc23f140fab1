// Ground-truth Doppler LiDAR + IMU simulator: the public entry point.
// Every simulated number is exactly consistent with the ground truth it exports.
#pragma once

#include <freeinit/sim/scenario.h>
#include <freeinit/sim/trajectory.h>
#include <freeinit/types.h>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace freeinit::sim {

/// What each simulated point is, for tests and plots (not visible to the estimator).
enum class PointLabel : std::uint8_t { Static = 0, Dynamic = 1, Outlier = 2 };

/// A simulated recording with its ground truth.
struct Recording {
  ScenarioConfig config;
  std::vector<ImuSample> imu;
  std::vector<LidarFrame> frames;
  std::vector<std::vector<PointLabel>> labels;  ///< labels[f][i] for frames[f].points[i]
  Extrinsics extrinsics;                        ///< TRUE LiDAR pose in the body frame
  /// What a user would declare to the estimator (config.declared_*: possibly wrong); a recording
  /// written for the estimator carries these.
  Extrinsics declared_extrinsics;
  /// [s] true LiDAR clock minus IMU clock: frames[f].stamp = true frame start + this. The points'
  /// true (IMU-clock) time is stamp - lidar_time_offset + time_offset.
  double lidar_time_offset = 0;
  Vec3 b_g = Vec3::Zero();                       ///< [rad/s] true constant gyro bias
  Vec3 b_a = Vec3::Zero();                       ///< [m/s^2] true constant accel bias
  Vec3 g_w = Vec3(0, 0, -kGravity);              ///< gravity in the simulator world (z up)
  std::shared_ptr<const Trajectory> trajectory;  ///< exact body trajectory
  std::shared_ptr<const Scene> scene;            ///< the scene that was ray cast (scene.h)
  TruthState truth(double t) const { return trajectory->at(t); }
  /// [s] true (IMU-clock) time of a point of frame `frame`.
  double pointTime(const LidarFrame& frame, const DopplerPoint& p) const {
    return frame.stamp - lidar_time_offset + static_cast<double>(p.time_offset);
  }
};

/// Names of all presets (Table I of the paper plus tunnel variants).
std::vector<std::string> presetNames();

/// The scenario of a preset, filled completely (presets.h); throws std::invalid_argument on an
/// unknown name.
ScenarioConfig preset(const std::string& name, std::uint64_t seed = 1);

/// Called after each simulated frame with (frames done, frames in all).
using SimulationProgress = std::function<void(std::size_t, std::size_t)>;

/// Generates a recording from the config alone. Deterministic for a given config (including seed).
/// Throws std::invalid_argument (validateScenario) on a config it cannot run. `progress`, if
/// given, is called after each frame.
Recording simulate(const ScenarioConfig& config, const SimulationProgress& progress = {});

/// The number of LiDAR frames simulate() makes for `config`.
std::size_t frameCount(const ScenarioConfig& config);

}  // namespace freeinit::sim
