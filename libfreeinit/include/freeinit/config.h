// All tunable parameters of Free-Init, grouped one struct per concern (one INI section each).
// Defaults are the values the accuracy tests and benchmarks use; units in brackets.
//
// Parameter structs, here and everywhere in the project, are free structs named `<Concept>Params`
// (plain aggregates with their defaults in the body), declared in the header of the component
// they configure, one INI section each. Each has one INI declaration (config_section.h: key
// names, units, accepted ranges, one-line docs, what reads each key, former names; defaults are
// the struct's own), a function `<section>Section()` beside its loader, which drives loading,
// validation, the effective-configuration echo and the checks that the shipped ini/*.ini files
// document every key. The estimator's sections are named by what reads them (FreeInitConfig);
// a component that takes keys of several of them has its own struct, not an INI section, built
// from the configuration by a function beside it (velocimeterParams(), gravityParams(),
// startDetectorParams(), ...).
#pragma once

#include <freeinit/types.h>

#include <cstddef>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

namespace freeinit {
namespace config {
class IniFile;
class Checker;
class SectionBase;
template <class S>
class Section;
}  // namespace config

/// Which estimator solves the window. INI section [estimator].
struct EstimatorParams {
  enum class Method {
    /// One Doppler-aided inertial filter and smoother over the window: attitude, velocity and
    /// both biases at once, the accelerometer in the propagation from the first instant
    /// (doppler_inertial_filter.h). Reaches the physical limit of the data.
    Joint,
    /// The paper's two stages: the Doppler-inertial velocimeter, then the accelerometer bias and
    /// gravity solve (velocimeter.h, gravity_estimator.h). Kept as the paper's reference.
    Paper,
  };
  Method method = Method::Joint;
};

/// The initialization window. INI section [window].
struct WindowParams {
  /// [s] window length (paper: ~100 IMU samples at 200 Hz). The window holds the IMU samples
  /// from its first one, t_0, up to t_0 + duration (exclusive; see windowSample()): 0.5 s is 100
  /// samples at 200 Hz and 500 at 1 kHz, whatever the IMU's rate.
  double duration = 0.5;
};

/// The IMU's noise and bias model: what both estimators assume of the IMU before the window's
/// data. INI section [imu].
struct ImuParams {
  double gyro_sigma = 0.002;             ///< [rad/s] gyro white noise per sample
  double accel_sigma = 0.02;             ///< [m/s^2] accelerometer white noise per sample
  Vec3 gyro_bias_prior = Vec3::Zero();   ///< [rad/s] initial gyro bias (e.g. from a calibration)
  double gyro_bias_sigma0 = 0.015;       ///< [rad/s] initial gyro bias std (typical MEMS)
  double gyro_bias_random_walk = 1e-4;   ///< [rad/s/sqrt(s)] gyro bias driving noise
  double accel_bias_prior_sigma = 0.1;   ///< [m/s^2] zero-mean prior (typical MEMS, ~10 mg)
  double accel_bias_bound = 0.5;         ///< [m/s^2] |b_a| per axis is kept below this
  double accel_bias_random_walk = 1e-3;  ///< [m/s^2/sqrt(s)] accelerometer bias driving noise
  // Gross faults and gaps (joint estimator; the screen in imu_screen.h): a sample no motion
  // explains is replaced by the value its neighbours imply, with the noise of that
  // interpolation, never integrated as read.
  double gyro_range = 34.9;    ///< [rad/s] per axis: a reading at or beyond it is a fault
  double accel_range = 156.9;  ///< [m/s^2] per axis (16 g)
  /// [-] a reading farther than this many robust sigmas (and a physical floor) from the cubic
  /// through its four neighbours, on both sides, is a fault.
  double fault_sigmas = 8.0;
  /// [-] the window declines (not_enough_data) when more than this share of its samples are
  /// faults.
  double max_fault_share = 0.05;
  /// [s] a gap in the IMU stream up to this long is bridged by interpolated samples whose noise
  /// grows with the gap; a longer one inside the window declines it, as does missing more than
  /// this much in all.
  double max_bridged_gap = 0.1;
};

/// The Doppler LiDAR's noise and which of its returns are used. INI section [doppler].
struct DopplerParams {
  double doppler_sigma = 0.03;           ///< [m/s] Doppler noise std
  bool doppler_ego_compensated = false;  ///< input Doppler already has the ego motion removed
  double min_range = 1.0;                ///< [m] closer points are skipped
  double max_range = 150.0;              ///< [m]
  /// Use one point in N (1: every point; 0: automatic, from max_point_rate).
  int point_stride = 0;
  /// [points/s] with point_stride = 0, the stride that brings the points used closest to this
  /// rate, from the first frame's density. The default uses every point of the FMCW LiDARs
  /// there are (an Aeva-like 600k points/s, 2.4M points/s of 120,000-point frames at 20 Hz) and
  /// halves only beyond 3M points/s: the Doppler-limited errors grow as the square root of the
  /// stride, and at a stride of 6 they exceeded 3x the Cramer-Rao bound of the data (a handheld
  /// start at 700k points/s: gravity 0.54 deg against a 0.16 deg bound; every point: 0.07 deg).
  double max_point_rate = 2.0e6;
  // Gating of dynamic points and gross outliers, on the Doppler residual.
  double gate_sigma = 4.0;  ///< [-] reject |r| > gate_sigma * sqrt(S) ...
  double gate_min = 0.15;   ///< [m/s] ... but never below this
  double gate_rel = 0.01;   ///< [-] ... plus this fraction of the LiDAR speed
};

/// The start decision: what moves at the window start, and whether the platform stands. The
/// joint estimator decides it over a short span (start_detector.h); the paper's form from its
/// robust start ([paper_bootstrap]) and the rest keys here. INI section [start].
struct StartParams {
  double duration = 0.1;  ///< [s] span of the joint estimator's start decision
  int points = 3000;      ///< returns of that span used (evenly spread), at most
  /// [1/(m/s)^2] smallest eigenvalue of the velocity information of the start's returns: below
  /// it their directions do not constrain the velocity (DegenerateGeometry).
  double min_info_eigen = 100.0;
  /// Use a start at rest: zero velocity (and rate) while the sensors show rest (joint), the
  /// zero-velocity mode (paper).
  bool detect_rest = true;
  double rest_speed = 0.05;  ///< [m/s] LiDAR speed below which the platform is at rest
};

/// The joint filter and smoother's own settings (doppler_inertial_filter.h). INI section
/// [joint].
struct JointParams {
  /// [rad] std of roll and pitch at the window start, about the start decision's gravity: large,
  /// so that the tilt comes from the window's data (the yaw is the world's gauge).
  double initial_tilt_sigma = 0.2;
  int max_iterations = 6;  ///< smoother (Gauss-Newton) iterations, at most
  /// [Hz] the filter's nodes at about this rate, at every m-th IMU sample, m = max(1,
  /// round(IMU rate / node_rate)); the samples between two nodes are all integrated, so a fast
  /// IMU's information is kept while a window's cost no longer grows with its rate (0: a node
  /// at every IMU sample). An IMU below 1.5 times the rate has a node at every sample.
  double node_rate = 200.0;
  /// While the IMU shows rest, the platform does not rotate: the gyro then measures its bias.
  bool zero_rate_at_rest = true;
  /// The gyro's white noise carried through the lever arm into the LiDAR velocity of all the
  /// returns of an IMU sample is modelled (false: taken as exact, as the paper does; the
  /// covariance is then optimistic on rigs with a long lever arm and many returns per sample).
  bool lever_arm_gyro_noise = true;
  /// [m/s] std of the zero body velocity while the IMU shows rest (gentle: the Doppler measures
  /// the velocity anyway; this mostly adds the vertical the field of view sees poorly).
  double rest_velocity_sigma = 0.005;
  /// [deg] std of the declared LiDAR-IMU rotation's error per axis, estimated jointly (0: taken
  /// as exact, the default: estimating it costs accuracy wherever the motion barely observes it;
  /// the calibration test below still checks it).
  double calibration_rotation_sigma_deg = 0.0;
  /// [s] std of the LiDAR-IMU clock offset (LiDAR clock minus IMU clock) about zero, estimated
  /// jointly from the start decision on (0: taken as exact). Where the motion observes it (a
  /// changing acceleration or rotation) the data give it, elsewhere it keeps this prior and the
  /// covariance carries it. 10 ms: clocks synchronized by software (driver or bag stamps).
  double time_offset_sigma = 0.01;
  /// The calibration test after the solve: the data's own estimate of a rotation error (this std
  /// per axis, [deg]) and a clock offset (this std, [s]). A significant one (99.9 %) is a
  /// warning; so is a body velocity whose uncertainty such errors would dominate (the window's
  /// motion does not verify the calibration). 0: no test.
  double test_rotation_sigma_deg = 2.0;
  double test_time_offset_sigma = 0.01;
};

/// The paper's Doppler-inertial velocimeter's own model (paper Sec. III-B; velocimeter.h), also
/// the Doppler-inertial odometry's. INI section [paper_velocimeter].
struct PaperVelocimeterParams {
  double vel_random_walk = 10.0;   ///< [m/s^2/sqrt(Hz)] v_l, v_b random walk density
  double omega_random_walk = 1.0;  ///< [rad/s^2/sqrt(Hz)] omega_b random walk density
  /// [m/s^2/sqrt(Hz)] v_l, v_b random walk density in the accelerometer-aided refinement passes
  double aided_vel_random_walk = 0.03;
  double gyro_bias_tau = 1000.0;      ///< [s] Gauss-Markov correlation time of the gyro bias
  bool kinematic_propagation = true;  ///< add -omega x v and the gyro slope to the propagation
  /// Let the Doppler update omega_b and b_g through the lever arm (the paper's full update).
  /// Off: they are Schmidt "consider" states of the Doppler update (their uncertainty enters the
  /// gain, their estimates come from the gyro and the gravity solve), so velocity-model errors at
  /// speed cannot bend the attitude or the gyro bias through a few cm of lever arm.
  bool doppler_updates_omega = false;
};

/// The paper's robust start of the LiDAR velocity from the first points (IRLS; also its motion
/// check in the zero-velocity mode). INI section [paper_bootstrap].
struct PaperBootstrapParams {
  int points = 4000;          ///< number of first points used
  int iterations = 10;        ///< IRLS iterations
  double cauchy_scale = 0.1;  ///< [m/s] IRLS Cauchy scale
  double prior_sigma = 40.0;  ///< [m/s] weak prior on each velocity axis
};

/// The paper form's zero-velocity mode at a start at rest ([start] detect_rest, rest_speed).
/// INI section [paper_rest].
struct PaperRestParams {
  double max_gyro_dev = 0.03;   ///< [rad/s] gyro deviation from its mean at rest
  double zupt_sigma = 0.002;    ///< [m/s], [rad/s] zero-velocity pseudo-measurement std
  double check_period = 0.025;  ///< [s] how often motion is checked
};

/// How the accelerometer bias and gravity are solved for.
enum class GravityFormulation {
  Integrated,      ///< velocity differences vs integrated specific force (default)
  Differentiated,  ///< the paper's form: numerically differentiated, low-pass filtered velocities
};

/// The paper's accelerometer bias and gravity solve (paper Sec. III-C; gravity_estimator.h).
/// INI section [paper_gravity].
struct PaperGravityParams {
  GravityFormulation formulation = GravityFormulation::Integrated;
  bool use_body_equation = true;    ///< residuals of the body kinematics
  bool use_lidar_equation = true;   ///< residuals of the LiDAR kinematics (lever arm terms)
  double lowpass_cutoff_hz = 10.0;  ///< [Hz] for the differentiated formulation (<= 0: off)
  /// [s] correlation time of the velocimeter's velocity error, modelled as first-order
  /// Gauss-Markov (AR(1)) with the samples' covariance as its stationary covariance; the
  /// integrated residuals are then whitened in time (quasi-differenced). 0: white errors.
  double velocity_error_correlation_time = 0.0;
  /// The body and LiDAR velocities come from the same points (as in the velocimeter): when both
  /// equations are used each gets half the information, so that together they count it once
  /// (integrated formulation; the differentiated one weighs both fully, as the paper).
  bool equations_share_errors = true;
  double loss_scale = 3.0;  ///< Cauchy loss scale on whitened residuals [sigma]
  int max_iterations = 50;  ///< Ceres iterations, at most
  /// Estimate a correction of the gyro bias with the integrated formulation (needs the gyro
  /// bias covariance, see GravityEstimator::estimate()).
  bool estimate_gyro_bias = true;
};

/// The paper form's passes over the window. INI section [paper_passes].
struct PaperPassesParams {
  /// Accelerometer-aided refinement passes over the window after the paper's pass: each reruns
  /// the velocimeter with the body acceleration from the accelerometer, the last b_a and
  /// gravity, then solves b_a and gravity again (0: the paper's single pass).
  int refinement_passes = 1;
  /// Extra decimation of the passes that only seed a refinement (their velocities serve the
  /// first gravity estimate; the last pass uses [doppler] point_stride).
  int seed_pass_stride = 3;
  /// [s] length of the passes that only seed a refinement, from the window start (0 or more
  /// than the window: the whole window). Shorter than the window, the last pass starts while
  /// the window is still being received, so an online user waits only for the last frame and
  /// the last solve instead of one more pass over the window. Seeding from 0.3 s instead of
  /// 0.5 s changed the mean gravity error over 13 presets x 3 seeds from 0.641 to 0.639 deg
  /// (`freeinit-eval --seeds 3 --no-baselines --duration 0.7` with `--seed-samples 0` and
  /// without; 60 samples are 0.3 s at the presets' 200 Hz).
  double seed_duration = 0.3;
};

/// Where an IMU sample stands in a span of `duration` seconds that starts at the sample at
/// t_first (the window, or a seed pass). The span holds the samples with t - t_first < duration;
/// a sample closes it (Last) when the next one is due at or after its end, t + (t - t_prev) >=
/// t_first + duration, so that a live stream need not wait for the first sample beyond the
/// window; times within 1 % of a sample interval of the end count as at the end (rounding of
/// stamps). A sample that comes after a gap beyond the end is Outside: the span closed with the
/// one before it. The span's first sample is always Inside.
enum class WindowSample { Inside, Last, Outside };
/// `t_prev`: the sample before `t` (t_prev < t; for the first sample pass t_prev = t).
WindowSample windowSample(double t_first, double t_prev, double t, double duration);
/// The window rule with the stream's nominal sample interval [s] (e.g. the median of its first
/// intervals) as the prediction of the next stamp, instead of the last interval: a sample closes
/// the span when t + interval >= t_first + duration (within 1 % of the interval), one at or
/// beyond the end is Outside. A gap inside the span then does not close it early (with the last
/// interval, a sample after a 0.2 s gap predicted its successor beyond a 0.5 s window).
WindowSample windowSampleAt(double t_first, double t, double interval, double duration);
/// The median of the first (up to 20) intervals from imu[first] [s] (0 with fewer than 2 samples).
double nominalInterval(const std::vector<ImuSample>& imu, std::size_t first);
/// The index of the last sample of the span that starts at imu[first] (windowSampleAt with
/// nominalInterval), or nullopt if the samples end before it closes.
std::optional<std::size_t> windowLastSample(const std::vector<ImuSample>& imu, std::size_t first,
                                            double duration);

/// Everything. The INI file has one section per member but the extrinsics (the app's
/// [extrinsics]). The sections are named by what reads them: [estimator] and [window] both
/// estimators, [imu] and [doppler] the sensors' models both use, [start] the start decision,
/// [joint] the joint estimator's own settings, [paper_*] the paper form's. Each key's
/// declaration (config.cpp) says which estimator reads it; the names of the earlier layout
/// ([velocimeter], [gravity], [bootstrap], [static_detector], and keys of [estimator] and
/// [window]) are still read, with a notice.
struct FreeInitConfig {
  EstimatorParams estimator;
  WindowParams window;
  ImuParams imu;
  DopplerParams doppler;
  StartParams start;
  JointParams joint;
  PaperVelocimeterParams paper_velocimeter;
  PaperBootstrapParams paper_bootstrap;
  PaperRestParams paper_rest;
  PaperGravityParams paper_gravity;
  PaperPassesParams paper_passes;
  Extrinsics extrinsics;
  /// Throws config::ConfigError (a std::invalid_argument) naming the offending key
  /// ("configuration key doppler.doppler_sigma: ...") if a value is out of its accepted
  /// range or the keys contradict each other.
  void validate() const;
  /// Loads the estimator's sections (sections()) of `ini` over the current values; other
  /// sections are the caller's. Keys given under their former names (formerSectionNames() and
  /// moved keys of current sections) are read as their current ones, with one notice line each
  /// ("file:line: [velocimeter] doppler_sigma is now [doppler] doppler_sigma (the old name is
  /// read for now)") appended to `notices`, or written to std::cerr when it is null. Throws
  /// config::ConfigError naming the file, the line, the section and the key (a key given under
  /// both names is one).
  void load(const config::IniFile& ini, std::vector<std::string>* notices = nullptr);
  /// Writes those sections, with their current names, as a documented INI that loads back to
  /// the same values.
  void dump(std::ostream& out) const;
  /// The declarations of those sections, in the order of the dump.
  static std::vector<const config::SectionBase*> sections();
  /// Their names.
  static std::vector<std::string> sectionNames();
  /// The sections of the earlier layout that no longer exist but are still read (their keys
  /// moved): a file may have them.
  static std::vector<std::string> formerSectionNames();
};

/// The INI declarations of the estimator's sections (the one place their keys are written).
const config::Section<EstimatorParams>& estimatorSection();
const config::Section<WindowParams>& windowSection();
const config::Section<ImuParams>& imuSection();
const config::Section<DopplerParams>& dopplerSection();
const config::Section<StartParams>& startSection();
const config::Section<JointParams>& jointSection();
const config::Section<PaperVelocimeterParams>& paperVelocimeterSection();
const config::Section<PaperBootstrapParams>& paperBootstrapSection();
const config::Section<PaperRestParams>& paperRestSection();
const config::Section<PaperGravityParams>& paperGravitySection();
const config::Section<PaperPassesParams>& paperPassesSection();

}  // namespace freeinit
