// The complete description of one simulated recording. simulate() reads nothing else: a preset
// and a randomized scenario are both just a filled ScenarioConfig, and a scenario INI file
// (scenario_ini.h) holds every field, so writing it and reading it back gives the same recording.
//
// Frames: the motion is described in a path frame (x the direction of travel, z up, ground at
// z = 0) in which the scene is laid out; `motion.heading_deg` turns path frame, scene and motion
// together about the world z axis. The rig r (the platform carrying LiDAR and IMU) follows the
// motion's six channels; the IMU (body b) sits on it at `motion.imu_mount_rpy_deg`; the LiDAR l
// sits in the body frame at the true extrinsics `lidar_rpy_deg`, `lidar_position`.
#pragma once

#include <freeinit/sim/analytic_trajectory.h>
#include <freeinit/sim/scene_builders.h>

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace freeinit::sim {

/// Order in which the scan lines of a frame are measured.
enum class LineOrder : std::uint8_t {
  TopDown = 0,      ///< line 0 (top) first, then 1, 2, ...
  BottomUp = 1,     ///< the bottom line first
  Interleaved = 2,  ///< the even lines top-down, then the odd lines top-down (two fields a frame)
};

/// Azimuth direction of each scan line.
enum class LineDirection : std::uint8_t {
  Alternating = 0,  ///< -hfov/2 -> +hfov/2 on even scan slots, back on odd ones (boustrophedon)
  Forward = 1,      ///< every line -hfov/2 -> +hfov/2
};

/// Motion of the rig in the path frame: the AnalyticTrajectory channels plus the mounting.
/// Attitudes are z-y-x: R = Rz(yaw) Ry(pitch) Rx(roll).
struct MotionConfig {
  Vec3 start_position = Vec3::Zero();     ///< [m] rig (= IMU origin) at the end of the standstill
  Vec3 start_rpy_deg = Vec3::Zero();      ///< [deg] rig roll, pitch, yaw at that instant
  std::array<ScalarSignal, 3> pos;        ///< x, y, z motion signals [m]
  std::array<ScalarSignal, 3> rpy;        ///< roll, pitch, yaw motion signals [rad]
  double still_until = 0;                 ///< [s] after t0: motion starts here (see blend)
  double blend_duration = 0;              ///< [s] smoothstep into motion; <= 0: moving throughout
  bool ramp_poly = false;                 ///< speed ramps up as S p' (analytic_trajectory.h)
  Vec3 imu_mount_rpy_deg = Vec3::Zero();  ///< [deg] IMU (body) on the rig: R_rb
  double heading_deg = 0;                 ///< [deg] yaw of the path frame in the world
};

/// Shape of an explicitly placed scene object.
enum class ObjectShape : std::uint8_t { Box = 0, Cylinder = 1 };

/// An explicitly placed object (a person crossing, a passing bus, ...), constant velocity.
struct SceneObject {
  ObjectShape shape = ObjectShape::Box;
  std::string label = "object";  ///< [a-z_] word for people reading the file: person, bus...
  Vec3 center = Vec3::Zero();    ///< [m] path frame, at t0
  Vec3 half_size =
      Vec3::Ones();              ///< [m] box: half extents; cylinder: (radius, radius, half height)
  double yaw = 0;                ///< [rad] box orientation about z
  Vec3 velocity = Vec3::Zero();  ///< [m/s] path frame; nonzero: a moving (Dynamic) object
  double reflectivity = 0.5;     ///< [-] in [0, 1]
};

/// The scene: a kind laid out by its builder (seeded by the scenario seed) plus explicit objects.
struct SceneConfig {
  std::string kind = "street";  ///< street, corridor, tunnel, open or parking
  /// true: the builder lays the scene out along the stretch the platform covers within the
  /// recording's duration (presets); false: along [x_min, x_max] for `horizon` seconds of moving
  /// objects, whatever the duration, so that a shorter recording has the same scene.
  bool auto_extent = true;
  double x_min = 0;          ///< [m] used when auto_extent is false
  double x_max = 50;         ///< [m]
  double horizon = 5;        ///< [s]
  StreetOptions street;      ///< kind street (x range and duration are filled by the simulator)
  CorridorOptions corridor;  ///< kind corridor
  TunnelOptions tunnel;      ///< kind tunnel
  OpenOptions open;          ///< kind open
  ParkingOptions parking;    ///< kind parking
  std::vector<SceneObject> objects;  ///< added to the built scene
};

/// Everything that defines one simulated recording. Presets (presets.h) and randomized scenarios
/// (random_scenario.h) fill it; users may edit it. A default-constructed config is preset dyna_01
/// with seed 1.
struct ScenarioConfig {
  ScenarioConfig();

  std::string name = "dyna_01";  ///< origin: a preset name or "random" (simulate() checks it)
  std::uint64_t seed = 1;        ///< seeds the scene layout, the noise and what `random_*` draws
  double t0 = 1700000000.0;      ///< [s] UNIX time of the first sample
  double duration = 5.0;         ///< [s]
  // Platform motion and scene.
  MotionConfig motion;
  SceneConfig scene;
  // LiDAR (Aeva Aeries II-like non-rotating raster)
  int points_per_frame = 60000;
  int lines = 64;
  double frame_rate = 10.0;  ///< [Hz]
  double hfov_deg = 120.0;
  double vfov_deg = 30.0;
  LineOrder line_order = LineOrder::TopDown;
  LineDirection line_direction = LineDirection::Alternating;
  double min_range = 0.5;       ///< [m]
  double max_range = 150.0;     ///< [m]
  double range_sigma = 0.02;    ///< [m]
  double doppler_sigma = 0.03;  ///< [m/s]
  double outlier_ratio = 0.01;  ///< fraction of points with a gross Doppler error
  // IMU
  double imu_rate = 200.0;    ///< [Hz]
  double gyro_sigma = 0.002;  ///< [rad/s] white noise per sample, nominal (datasheet) value
  double accel_sigma = 0.02;  ///< [m/s^2] white noise per sample, nominal (datasheet) value
  Vec3 gyro_sigma_scale = Vec3::Ones();   ///< [-] this unit's per-axis sigma / gyro_sigma
  Vec3 accel_sigma_scale = Vec3::Ones();  ///< [-] this unit's per-axis sigma / accel_sigma
  bool random_biases = true;              ///< draw b_g, b_a from the preset ranges with the seed
  Vec3 b_g = Vec3::Zero();                ///< [rad/s] used when random_biases is false
  Vec3 b_a = Vec3::Zero();                ///< [m/s^2] used when random_biases is false
  // True calibration: R_bl = Rz(yaw) Ry(pitch) Rx(roll), each angle plus a uniform draw in
  // +-lidar_rpy_jitter_deg, and p_bl = lidar_position plus a uniform draw in
  // +-lidar_position_jitter per axis (the draws use the seed; presets perturb their nominal
  // extrinsics this way).
  Vec3 lidar_rpy_deg = Vec3::Zero();   ///< [deg]
  Vec3 lidar_position = Vec3::Zero();  ///< [m] p_bl
  double lidar_rpy_jitter_deg = 0;     ///< [deg]
  double lidar_position_jitter = 0;    ///< [m]
  // What a user declares to the estimator, wrong by these (undeclared) amounts:
  // R_bl,declared = R_bl Exp(declared_rotation_error_deg), p_bl,declared = p_bl +
  // declared_position_error.
  Vec3 declared_rotation_error_deg = Vec3::Zero();  ///< [deg] rotation vector
  Vec3 declared_position_error = Vec3::Zero();      ///< [m]
  /// [s] LiDAR clock minus IMU clock: every LiDAR stamp in the recording is the true (IMU-clock)
  /// time of its frame start plus this.
  double lidar_time_offset = 0;

  /// Per-axis white noise sigmas of this unit [rad/s], [m/s^2].
  Vec3 gyroSigmaPerAxis() const { return gyro_sigma * gyro_sigma_scale; }
  Vec3 accelSigmaPerAxis() const { return accel_sigma * accel_sigma_scale; }
};

/// The checks of the scenario INI's keys (scenario_ini.h: ranges and checks across keys) on a
/// config built in code: throws config::ConfigError (a std::invalid_argument) "configuration key
/// scenario.<key>: <what is wrong>" for a config simulate() cannot run.
void validateScenario(const ScenarioConfig& config);

/// The rig/IMU trajectory of a config (t0 = config.t0).
std::shared_ptr<const AnalyticTrajectory> makeTrajectory(const ScenarioConfig& config);

/// The scene of a config, in the world frame (the path frame turned by the heading).
std::shared_ptr<const Scene> makeScene(const ScenarioConfig& config, const Trajectory& trajectory);

/// The true LiDAR-IMU extrinsics of a config (with the seeded jitter).
Extrinsics makeExtrinsics(const ScenarioConfig& config);

/// The extrinsics a user declares: the true ones off by the config's declared errors.
Extrinsics declaredExtrinsics(const ScenarioConfig& config, const Extrinsics& truth);

}  // namespace freeinit::sim
