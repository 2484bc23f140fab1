// Randomized scenarios: randomScenario(seed) draws a complete ScenarioConfig over what real Doppler
// LiDAR + IMU rigs do, so that an estimator can be measured on data it was never tuned on. The
// same seed always gives the same config (and simulate() the same recording). Every aspect is
// drawn from its own seeded stream.
//
// Frames (scenario.h): the rig follows the motion in a path frame whose x axis is the direction of
// travel; the LiDAR looks forward from the rig, the IMU is mounted on the rig at a rotation of tens
// of degrees; the whole layout is turned by a random heading.
//
// Distribution. U(a, b) uniform, logU log-uniform, {..} a uniform choice, p probability.
// clang-format off
//
// | aspect | distribution | why |
// |---|---|---|
// | platform class | handheld p 0.4, wheeled 0.3, vehicular 0.3 | every class well represented (>= 20 % each) |
// | scene (handheld) | street 0.3, corridor 0.2, parking 0.2, open 0.15, tunnel 0.15 | where people carry a rig |
// | scene (wheeled) | street 0.3, open 0.2, parking 0.2, corridor 0.15, tunnel 0.15 | delivery / inspection robots |
// | scene (vehicular) | street 0.4, parking 0.25, tunnel 0.2, open 0.15 | roads, car parks, tunnels, open roads |
// | start | moving from the first instant p 0.4 (at cruise speed), starting within 0.6 s p 0.2 (rest U(0, 0.6) s), static start p 0.4 (rest U(0.6, 2) s) | the three ways an initializer's window begins; >= 25 % at rest for the first 0.6 s |
// | getting going | ramped start (speed = S(t) x cruise, no overshoot) over 1.875 v / a_peak: a_peak handheld U(1, 3), wheeled U(0.5, 2), vehicular U(1, 3) m/s^2 (at least 0.3 / 0.5 / 1 s); rotating by hand U(0.3, 1) s | the accelerations people, robots and cars start with |
// | handheld motion | rotating by hand p 0.45 (U(0, 1.2) m/s), walking 0.35 (U(0.6, 1.8) m/s), running 0.2 (U(2.5, 5) m/s; corridor <= 3) | the handheld starts the paper studies, plus plain walking |
// | handheld rotation | 1-2 sinusoids per attitude axis at U(0.8, 3) Hz, random phases, axis weights U(0.2, 1), scaled so that the peak body rate over the 6 s (sampled at 500 Hz, the blend into motion included) is a target U(1.5, 12) rad/s; amplitude <= 1 rad (faster instead of wider) | wrist rotations a person makes to excite an IMU, up to 12 rad/s |
// | gait | step U(1.6, 2.2) Hz walking, U(2.6, 3.2) Hz running; bob U(0.01, 0.035) / U(0.03, 0.07) m, its 2nd harmonic, surge, sway at half the step rate, attitude sway | measured walking/running kinematics |
// | hand shake | 2 sinusoids per attitude axis U(0.002, 0.012) rad at U(2, 8) Hz, 1 per position axis U(1, 6) mm at U(2, 6) Hz | tremor of a held device |
// | wheeled speed | U(0.3, 5) m/s (corridor <= 2, parking <= 3), acceleration U(-0.15, 0.3) m/s^2 (never below half the speed within 6 s) | robots from slow indoor to fast outdoor |
// | wheeled bounce, vibration | z 2 x U(0.5, 4) mm at U(4, 15) Hz; roll, pitch 2 x U(0.5, 5) mrad at U(4, 15) Hz and U(1, 12) mrad at U(0.5, 2) Hz | small wheels on uneven floors |
// | vehicular speed | street U(3, 17), tunnel and open U(5, 30), parking U(1, 5) m/s; acceleration U(-0.5, 0.6) m/s^2 (as wheeled) | 0-30 m/s (108 km/h) |
// | vehicular bounce, vibration | suspension z U(3, 20) mm at U(1, 2.2) Hz, pitch/roll U(2, 10) mrad at U(0.7, 2.5) Hz; road z U(0.5, 3) mm, roll/pitch U(0.3, 2) mrad at U(8, 15) Hz; surge U(0, 0.3) m at U(0.1, 0.3) Hz | car body and road roughness |
// | turning | wheeled/vehicular: yaw sinusoid U(0.05, 0.3) Hz, amplitude <= 0.3 / 0.05 rad, the lateral motion following it (no side slip), <= 0.3 / 0.5 m | lane keeping, gentle curves |
// | handheld wander | yaw U(0, 0.25) rad at U(0.05, 0.3) Hz, roll and pitch U(0, 0.08) rad at U(0.1, 0.5) Hz, lateral U(0, 0.15) m (corridor 0.05) | where a hand points drifts |
// | heading | U(-180, 180) deg | no preferred world direction |
// | base tilt (rig roll/pitch at the start) | handheld U(0, 30), wheeled U(0, 12), vehicular U(0, 8) deg in a uniform direction | a tilted hand, ramps, road grade |
// | rig yaw vs. path | handheld U(-40, 40) deg, others U(-3, 3) deg | a hand-held rig is not pointed where one walks |
// | where | street: sidewalk 1.8 m from the facades (vehicular: lane y = -2.5); corridor: centre +-0.1 m; tunnel: 1 m from the wall (vehicular: lane centre); parking: aisle (handheld +-1 m); IMU height handheld U(1, 1.6), wheeled U(0.3, 0.9), vehicular U(1.2, 2.2) m | clear of the scene's objects |
// | street | half width U(8.5, 16) m, cars U(0, 10) per 100 m and lane, pedestrians U(0, 16) per 100 m and sidewalk | narrow to wide streets, empty to busy |
// | corridor | half width U(1.3, 2.5) m, height U(2.4, 4) m; people only as movers (below) | offices, hospitals |
// | tunnel | half width U(2, 6) m (vehicular U(4.5, 8)), height U(2.6, 6) m (vehicular U(4.5, 7.5)); features: none p 0.4, else U(2, 20) per 100 m | pedestrian to road tunnels, featureless or lit |
// | open | 0-6 people at 8-14 m | fields, squares |
// | parking | aisle half width U(3, 4.5) m, occupancy U(0.3, 0.95), 0-4 people, 0-3 cars driving | car parks |
// | movers in view | static starts p 0.8 (1-3 objects), others p 0.35 (1-2), placed to move through the field of view in the first 0.6 s (seen at >= 2 of the instants 0.1, 0.2, ..., 0.6 s): people crossing at U(1, 5) m (vehicular U(4, 12) m) at U(0.8, 1.8) m/s, people walking towards or away, cyclists, cars, vans, buses and trucks crossing at U(3, 10) m (vehicular U(6, 15) m) or passing along the lanes of streets, tunnels and aisles; each checked visible from the start pose (not hidden by the scene) and clear of the platform | people crossing close in front of a standing sensor, traffic, a bus filling the view |
// | scan pattern | line order top-down p 0.5, interleaved (even then odd lines) 0.35, bottom-up 0.15; direction alternating 0.6, every line the same way 0.4 | the raster patterns of non-rotating FMCW LiDARs |
// | scan size | lines {16, 32, 48, 64, 96, 128}; points per frame logU(10,000, 120,000); frame rate {10, 12.5, 15, 20} Hz; hfov U(90, 125) deg, vfov U(20, 40) deg | device families and modes |
// | LiDAR noise | range sigma U(0.01, 0.05) m, Doppler sigma logU(0.02, 0.05) m/s, outliers U(0, 0.03), min range U(0.3, 0.8) m, max range U(150, 250) m | FMCW datasheets |
// | IMU rate | {100, 150, 200, 250, 400} Hz | common MEMS output rates |
// | IMU white noise | density gyro logU(5e-5, 3e-4) rad/s/sqrt(Hz), accel logU(6e-4, 3e-3) m/s^2/sqrt(Hz); per-sample sigma = density sqrt(rate) (gyro_sigma, accel_sigma: the datasheet value), each axis x U(0.8, 1.2) (the *_sigma_scale) | consumer to industrial MEMS (ICM-42688 .. BMI088 .. MPU-9250) |
// | IMU biases | per axis N(0, 0.015 rad/s) and N(0, 0.1 m/s^2), truncated at 2 sigma (0.03 rad/s, 0.2 m/s^2) | the estimator's priors gyro_bias_sigma0 = 0.015 rad/s, accel_bias_prior_sigma = 0.1 m/s^2 (bound 0.5): never wider than they allow |
// | LiDAR on the rig | roll U(-3, 3), pitch U(-5, 5) handheld / U(0, 10) nose down otherwise, yaw U(-5, 5) deg | a forward-looking LiDAR |
// | IMU on the rig | rotation U(10, 60) deg about a uniform axis | IMUs mounted in any orientation: R_bl of tens of degrees about any axis |
// | lever arm p_bl | uniform direction, length U(0.02, 0.3) m | board-level to separate-box rigs |
// | wrong calibration | p 0.25; then each of: LiDAR time offset U(1, 10) ms either sign, declared rotation off U(0.3, 2) deg about a uniform axis, declared p_bl off U(0.5, 3) cm in a uniform direction, with p 0.6 each (at least one) | what users get wrong and do not declare |
// clang-format on
//
// The scene is laid out for the platform's first 6 s (scene_horizon), so a recording shorter or
// longer than the default 3 s (up to 6 s) has the same scene.
#pragma once

#include <freeinit/sim/simulator.h>

#include <cstdint>
#include <string>
#include <vector>

namespace freeinit::sim {

enum class PlatformClass : std::uint8_t { Handheld = 0, Wheeled = 1, Vehicular = 2 };

/// "handheld", "wheeled", "vehicular".
const char* platformName(PlatformClass platform);

/// What randomScenario(seed) drew, for reporting and for choosing subsets.
struct RandomScenarioInfo {
  std::uint64_t seed = 0;
  PlatformClass platform = PlatformClass::Handheld;
  std::string scene;             ///< scene kind
  std::string motion;            ///< rotating, walking, running, rolling or driving
  std::string start;             ///< moving, starting (within 0.6 s) or static
  bool static_start = false;     ///< at rest for at least the first 0.6 s
  double rest_duration = 0;      ///< [s] at rest from the first sample (0 when moving from it)
  double speed = 0;              ///< [m/s] cruise speed once moving
  double peak_angular_rate = 0;  ///< [rad/s] max |omega_b| over the first 6 s (the scene horizon)
  double base_tilt_deg = 0;      ///< [deg] rig tilt (roll/pitch) at the start
  double body_tilt_deg = 0;      ///< [deg] angle of the IMU's z axis from the vertical at the start
  int movers_in_view = 0;        ///< objects placed to move through the view in the first 0.6 s
  /// A static start with people or vehicles moving in view (movers_in_view > 0).
  bool dynamic_near_standing_sensor = false;
  bool calibration_wrong = false;     ///< the declared calibration differs from the truth
  double lidar_time_offset = 0;       ///< [s]
  double rotation_error_deg = 0;      ///< [deg] declared vs. true R_bl
  double position_error = 0;          ///< [m] declared vs. true p_bl
  double extrinsic_rotation_deg = 0;  ///< [deg] angle of the true R_bl
  double lever_arm = 0;               ///< [m] |p_bl|
  /// Share of the recording's points on moving objects: -1 until measured on a simulation
  /// (measureMovingPoints()).
  double moving_point_share = -1;
  double moving_point_share_first_0_6s = -1;  ///< the same over the first 0.6 s
};

/// A drawn scenario and what was drawn.
struct RandomScenario {
  ScenarioConfig config;
  RandomScenarioInfo info;
};

/// Draws scenario `seed` (config.name "random", config.seed = seed). Cheap: no simulation (the
/// scene layout is built once to check that the movers are visible).
RandomScenario drawRandomScenario(std::uint64_t seed);

/// drawRandomScenario(seed).config.
ScenarioConfig randomScenario(std::uint64_t seed);

/// One-line sentences describing the draw (for logs and the comment of a scenario INI).
std::vector<std::string> describe(const RandomScenarioInfo& info);

/// Share of the points whose true time is in [t_begin, t_end] [s] that lie on moving objects
/// (label Dynamic), from the recording's labels; 0 when there are no such points.
double movingPointShare(const Recording& rec, double t_begin = -1e300, double t_end = 1e300);

/// Fills info's moving-point shares from a simulation of its scenario.
void measureMovingPoints(RandomScenarioInfo& info, const Recording& rec);

/// A closed range [lo, hi] to draw a value from; lo == hi: exactly that value.
struct DrawRange {
  double lo = 0;
  double hi = 0;
};

/// What an evaluation hands the estimator instead of the truth, on purpose.
struct MisdeclarationRanges {
  /// [-] true / declared IMU noise (gyro and accelerometer alike), log-uniform; > 0.
  DrawRange imu_noise_factor{1, 1};
  /// [-] true / declared Doppler noise, log-uniform; > 0.
  DrawRange doppler_noise_factor{1, 1};
  /// [s] |undeclared LiDAR-IMU clock offset|, uniform, >= 0; its sign is drawn (+ or - alike).
  DrawRange time_offset{0, 0};
};

/// One run's draw from MisdeclarationRanges.
struct Misdeclaration {
  double imu_noise_factor = 1;      ///< [-] the estimator is handed the IMU noise / this
  double doppler_noise_factor = 1;  ///< [-] the estimator is handed the Doppler noise / this
  double time_offset = 0;           ///< [s] LiDAR clock minus IMU clock, not declared
};

/// The misdeclaration of run `seed`, from its own seeded stream (apart from every stream of the
/// scenario: the recording of a seed is the same whatever is drawn here, so runs with different
/// ranges are paired). Four uniform numbers are drawn in a fixed order whatever the ranges (IMU
/// factor, Doppler factor, offset size, offset sign), so each quantity's draw depends on its own
/// range only. A range of one value gives exactly that value (the offset's sign is still drawn).
/// Throws std::invalid_argument on a range out of order, a factor <= 0 or an offset < 0.
Misdeclaration drawMisdeclaration(std::uint64_t seed, const MisdeclarationRanges& ranges);

}  // namespace freeinit::sim
