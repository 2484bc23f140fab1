// Ground-truth Doppler LiDAR + IMU simulator: the public entry point.
// Every simulated number is exactly consistent with the ground truth it exports.
#pragma once

#include <freeinit/types.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace freeinit::sim {

class Scene;  // scene.h

/// Exact kinematic state of the body (IMU) frame at time t.
struct TruthState {
  double t = 0;                        ///< [s] UNIX time
  Mat3 R_wb = Mat3::Identity();        ///< body attitude in the (gravity-aligned, z up) world
  Vec3 p_w = Vec3::Zero();             ///< [m] body origin in w
  Vec3 v_w = Vec3::Zero();             ///< [m/s] body velocity in w
  Vec3 a_w = Vec3::Zero();             ///< [m/s^2] body acceleration in w
  Vec3 omega_b = Vec3::Zero();         ///< [rad/s] body angular velocity in b
  Vec3 alpha_b = Vec3::Zero();         ///< [rad/s^2] body angular acceleration in b
};

/// A C2-smooth trajectory whose derivatives are available analytically at any time.
class Trajectory {
 public:
  virtual ~Trajectory() = default;
  virtual TruthState at(double t) const = 0;
};

/// What each simulated point is, for tests and plots (not visible to the estimator).
enum class PointLabel : std::uint8_t { Static = 0, Dynamic = 1, Outlier = 2 };

/// Everything that defines one simulated recording. Presets fill it; users may edit it.
struct ScenarioConfig {
  std::string name = "dyna_01";
  std::uint64_t seed = 1;
  double t0 = 1700000000.0;      ///< [s] UNIX time of the first sample
  double duration = 5.0;         ///< [s]
  // LiDAR (Aeva Aeries II-like non-rotating raster)
  int points_per_frame = 60000;
  int lines = 64;
  double frame_rate = 10.0;      ///< [Hz]
  double hfov_deg = 120.0;
  double vfov_deg = 30.0;
  double min_range = 0.5;        ///< [m]
  double max_range = 150.0;      ///< [m]
  double range_sigma = 0.02;     ///< [m]
  double doppler_sigma = 0.03;   ///< [m/s]
  double outlier_ratio = 0.01;   ///< fraction of points with a gross Doppler error
  // IMU
  double imu_rate = 200.0;       ///< [Hz]
  double gyro_sigma = 0.002;     ///< [rad/s] white noise per sample
  double accel_sigma = 0.02;     ///< [m/s^2] white noise per sample
  bool random_biases = true;     ///< draw b_g, b_a from the ranges below with the seed
  Vec3 b_g = Vec3::Zero();       ///< [rad/s] used when random_biases is false
  Vec3 b_a = Vec3::Zero();       ///< [m/s^2] used when random_biases is false
  // Scene and motion are chosen by the preset name; see presets.h.
};

/// A simulated recording with its ground truth.
struct Recording {
  ScenarioConfig config;
  std::vector<ImuSample> imu;
  std::vector<LidarFrame> frames;
  std::vector<std::vector<PointLabel>> labels;  ///< labels[f][i] for frames[f].points[i]
  Extrinsics extrinsics;                        ///< true LiDAR pose in the body frame
  Vec3 b_g = Vec3::Zero();                      ///< [rad/s] true constant gyro bias
  Vec3 b_a = Vec3::Zero();                      ///< [m/s^2] true constant accel bias
  Vec3 g_w = Vec3(0, 0, -kGravity);             ///< gravity in the simulator world (z up)
  std::shared_ptr<const Trajectory> trajectory; ///< exact body trajectory
  std::shared_ptr<const Scene> scene;           ///< the scene that was ray cast (scene.h)
  TruthState truth(double t) const { return trajectory->at(t); }
};

/// Names of all presets (Table I of the paper plus tunnel variants).
std::vector<std::string> presetNames();

/// The scenario of a preset; throws std::invalid_argument on an unknown name.
ScenarioConfig preset(const std::string& name, std::uint64_t seed = 1);

/// Generates a recording. Deterministic for a given config (including seed).
Recording simulate(const ScenarioConfig& config);

}  // namespace freeinit::sim
