// The result of an initialization: the initial state of a LiDAR-inertial estimator, its covariance,
// the static map and diagnostics.
#pragma once

#include <freeinit/types.h>

#include <string>
#include <vector>

namespace freeinit {

/// Expected outcomes. Anything but Ok means "not initialized": never a confident wrong answer.
enum class InitStatus {
  Ok,
  NotEnoughData,       ///< the window is not covered by IMU and LiDAR data
  NoDoppler,           ///< no usable Doppler returns (all gated, or zero everywhere)
  DegenerateGeometry,  ///< the point directions do not constrain the velocity
  SolverFailed,        ///< the accelerometer bias / gravity problem has no usable solution
  AmbiguousMotion,     ///< the data cannot decide whether the platform or the scene moves
  InconsistentData,    ///< the measurements contradict each other beyond their noise (e.g. a
                       ///< wrong calibration): no state is reported
};

/// Short machine-friendly name of a status ("ok", "not_enough_data", ...).
const char* toString(InitStatus s);

/// Index of each block in the 18x18 covariance, order [dtheta p v b_g b_a g].
enum StateBlock : int { kTheta = 0, kPos = 3, kVel = 6, kBg = 9, kBa = 12, kGrav = 15 };
using Cov18 = Eigen::Matrix<double, 18, 18>;

/// The initial state x0 = [R_wb, p_w, v_w, b_g, b_a, g_w] (paper Sec. III-D).
/// World frame w: origin at the body position at the window start, z axis opposite to gravity,
/// yaw equal to the body yaw at the window start. Hence g_w = (0, 0, -9.81) and the roll/pitch
/// uncertainty is carried by the attitude block. dtheta is the right (body-frame) perturbation:
/// R_true = R_wb * Exp(dtheta).
struct InitialState {
  InitStatus status = InitStatus::NotEnoughData;
  std::string message;   ///< human-readable reason when status != Ok
  double timestamp = 0;  ///< [s] UNIX time the state refers to (window end)
  Quat q_wb = Quat::Identity();
  Vec3 p_w = Vec3::Zero();           ///< [m]
  Vec3 v_w = Vec3::Zero();           ///< [m/s] body (IMU origin) velocity in w
  Vec3 b_g = Vec3::Zero();           ///< [rad/s]
  Vec3 b_a = Vec3::Zero();           ///< [m/s^2]
  Vec3 g_w = Vec3(0, 0, -kGravity);  ///< [m/s^2]
  Cov18 cov = Cov18::Identity();
  /// [s] the LiDAR-IMU clock offset (LiDAR clock minus IMU clock: a return stamped t by the LiDAR
  /// was taken at IMU time t - time_offset) the state was estimated with, and its std
  /// (0: taken as exact, [joint] time_offset_sigma = 0 or the paper's estimator).
  double time_offset = 0;
  double time_offset_sigma = 0;
  /// The window's data determined the offset (its std below half the prior's); false: it is at
  /// its prior (mean and std within a fraction of them), and the covariance carries its share.
  bool time_offset_estimated = false;
  /// What a user must know about an Ok state (e.g. a bias at its bound, residuals larger than the
  /// configured noise): one sentence each. Empty when nothing is suspicious.
  std::vector<std::string> warnings;

  bool ok() const { return status == InitStatus::Ok; }
  /// Body velocity in the body frame.
  Vec3 v_b() const { return q_wb.conjugate() * v_w; }
  /// Gravity in the body frame.
  Vec3 g_b() const { return q_wb.conjugate() * g_w; }
};

/// A pose of the initialization trajectory (world frame as in InitialState).
struct PoseSample {
  double t = 0;  ///< [s] UNIX time
  Quat q_wb = Quat::Identity();
  Vec3 p_w = Vec3::Zero();
};

/// The velocimeter's estimate at one instant (recorded at every IMU sample).
struct VelocitySample {
  double t = 0;                   ///< [s] UNIX time
  Vec3 v_l = Vec3::Zero();        ///< [m/s] LiDAR velocity in l
  Vec3 v_b = Vec3::Zero();        ///< [m/s] body velocity in b
  Vec3 omega_b = Vec3::Zero();    ///< [rad/s] bias-free angular velocity in b
  Vec3 b_g = Vec3::Zero();        ///< [rad/s]
  Vec3 sigma_v_b = Vec3::Zero();  ///< [m/s] per-axis standard deviation of v_b
  bool stationary = false;        ///< zero-velocity mode active
};

/// A point of the map, in the world frame.
struct MapPoint {
  Eigen::Vector3f p_w = Eigen::Vector3f::Zero();  ///< [m]
  float intensity = 0;
  float residual = 0;  ///< [m/s] Doppler residual when it was processed
  float doppler = 0;   ///< [m/s] the return's measured Doppler (radial velocity, sign of types.h)
  float time = 0;      ///< [s] the return's time minus the state's timestamp (<= 0 in the window)
};

/// One white noise the estimator used, and where it came from. The configured values are a prior
/// that the window's data outweigh (joint estimator; the paper's pipeline uses them as given).
struct NoiseUsed {
  enum class Source {
    Declared,    ///< the configured value (the data could not tell, or were not asked)
    DataRest,    ///< the IMU's samples while at rest
    DataMoving,  ///< the IMU's samples while moving (their high-order differences)
    UpperBound,  ///< the motion hides the noise: an upper bound from the data
    Data,        ///< the Doppler residuals of the window's returns
  };
  /// The value used: gyro [rad/s] and accelerometer [m/s^2] per sample, Doppler [m/s] per return.
  double value = 0;
  double rel_sigma = 0;  ///< [-] relative 1-sigma of `value` (0: taken as given)
  double declared = 0;   ///< the configured value, same unit
  Source source = Source::Declared;
};
/// "declared", "data_rest", "data_moving", "upper_bound", "data".
const char* toString(NoiseUsed::Source s);

/// The white noises the estimator used.
struct NoiseReport {
  NoiseUsed gyro, accel, doppler;
};

/// Counters and timings, for users and for tests.
struct Diagnostics {
  std::size_t points_seen = 0;      ///< points inside the window
  std::size_t points_used = 0;      ///< points that passed the gate (at rest: consistent with
                                    ///< zero velocity) and are in the static map
  std::size_t points_skipped = 0;   ///< by decimation or range limits
  std::size_t points_rejected = 0;  ///< gated out as dynamic or outlier
  std::size_t gyro_updates = 0;
  double update_rate_hz = 0;   ///< velocimeter updates per second of data
  bool static_start = false;   ///< the window started at rest
  double static_duration = 0;  ///< [s] time spent in zero-velocity mode
  /// [s] of the window whose gyro samples measured the bias (the IMU at rest): the zero-velocity
  /// time, or longer when the returns showed a translation too gentle for the IMU (joint
  /// estimator: the zero velocity is then withdrawn, the zero rotation rate kept)
  double zero_rate_duration = 0;
  double doppler_residual_rms = 0;  ///< [m/s] RMS of the used points' Doppler residuals at the
                                    ///< estimate (compare with the configured Doppler noise)
  /// Chi-square per degree of freedom of the nodes' Doppler residuals (joint estimator,
  /// DopplerInertialFilter::nodeResiduals; 0: not tested): about 0.8-1 when the noise model
  /// holds; above its 99.9 % quantile the state's covariance is scaled up by it.
  double node_residual_ratio = 0;
  /// IMU samples of the window rejected as gross faults (joint estimator, ImuScreen): replaced
  /// by the value their neighbours imply, with that interpolation's noise, never integrated.
  std::size_t imu_faults = 0;
  /// [s] IMU gaps inside the window bridged by interpolated samples, in all (joint estimator).
  double imu_gap_s = 0;
  double window_duration = 0;         ///< [s] from the window start to the state time
  std::size_t frames_in_window = 0;   ///< LiDAR frames with points in the window
  bool imu_at_rest_at_start = false;  ///< the IMU showed only noise over the start decision's span
  int iterations = 0;                 ///< smoother iterations (joint estimator)
  NoiseReport noise;                  ///< the sensors' noise used, with its source
  /// [s] from the window start to the end of the data the early smoothing took (joint
  /// estimator: it runs once, at three quarters of the window, so that the final smoothing
  /// starts near its solution; 0 if it did not run)
  double early_smoothing_to = 0;
  /// [s] wall time of the estimator but its solver (time_solver), over every call, the one that
  /// closes the window included
  double time_velocimeter = 0;
  double time_solver = 0;  ///< [s] wall time of the smoothings or solves
  /// [s] wall time of the add*() / finish() call that made the state final: the latency from
  /// the last measurement the window needed to the state (what an online user waits for; the
  /// joint estimator's map comes after it, time_map).
  double time_to_result = 0;
  /// [s] wall time of the static map, built after the state (FreeInit::result()).
  double time_map = 0;
  std::string solver_report;
};

/// Everything an initialization produces.
struct InitResult {
  InitialState state;
  std::vector<MapPoint> static_map;    ///< static points mapped at their own time
  std::vector<MapPoint> rejected;      ///< gated-out points (dynamic objects, outliers)
  std::vector<PoseSample> trajectory;  ///< at every IMU sample of the window
  std::vector<VelocitySample> velocities;
  Diagnostics diag;
};

}  // namespace freeinit
