// What moves at the window start: the platform's velocity and gravity from the first instants,
// chosen among the motions the Doppler returns support, with every sensor's say.
//
// A Doppler return measures the velocity of the LiDAR relative to what it hits. The static world,
// a passing car and a bus filling the view each give a consistent set of returns; which one is the
// world is decided by how much of the field of view supports it (a moving object covers a small
// part of it, the world the rest) and by the IMU: a platform at rest shows only sensor noise in the
// gyro and the accelerometer, and a platform that moves can only have got there by accelerating.
//
// Model over the start span [0, T] ([start] duration; times from the window start, body frame b0
// at t = 0):
//   v_b(t) = R_0t^T (v_b0 + C(t) + g_b0 t),   C(t) = int_0^t R_0s f(s) ds,
// R_0t the body rotation since t = 0 from the gyro (prior bias removed), f the specific force.
// b_a is not separated from gravity over so short a span (g_b0 carries g_b0 - b_a). A return of
// direction d at time t, u = R_bl d, w = R_0t u, measures
//   z = -u^T (v_b(t) + omega(t) x p_bl)   <=>   z + u^T (omega x p_bl) + w^T C = -w^T v_b0 - t w^T
//   g_b0,
// linear in (v_b0, g_b0). Hypotheses are drawn by RANSAC on the first part of the span (gravity
// fixed at the mean specific force there), refined on the whole span by iteratively reweighted
// least squares (Cauchy) in all six unknowns, and scored by inliers and field-of-view coverage.
#pragma once

#include <freeinit/config.h>
#include <freeinit/types.h>

#include <string>
#include <vector>

#include "joint/noise_estimate.h"

namespace freeinit {

/// Settings of the start decision.
struct StartDetectorParams {
  double doppler_sigma = 0.03;     ///< [m/s]
  double gyro_sigma = 0.002;       ///< [rad/s] per sample (bounds the plausible rest levels)
  double accel_sigma = 0.02;       ///< [m/s^2] per sample (likewise)
  double gyro_bias_sigma = 0.015;  ///< [rad/s] prior std of the gyro bias (about b_g_prior)
  double accel_bias_bound = 0.5;   ///< [m/s^2] per axis (a standing IMU reads g within it)
  double gate = 0.15;              ///< [m/s] inlier threshold on the Doppler residual
  double max_speed = 0.05;         ///< [m/s] a refined speed below this is rest
  /// A rest hypothesis supported by at least this fraction of the best hypothesis' coverage wins
  /// when the IMU shows rest.
  double rest_coverage_ratio = 0.1;
  /// A second motion covering at least this share of the best one's view (and at least
  /// min_contender_coverage of the view) is a contender: which of the two is the world cannot be
  /// told from the Doppler and the IMU (an object moving at constant velocity is consistent with
  /// the IMU as well), so the start is ambiguous. A car passing a vehicle covers far less.
  double ambiguity_ratio = 0.25;
  double min_contender_coverage = 0.1;
  /// The ground check: the lowest `ground_share` of the returns (by height under the chosen
  /// motion's gravity, at least ground_depth below the sensor, at least 30 of them) are taken to
  /// be on the ground, which does not move. When the chosen motion explains at most
  /// ground_explained_max of them and another motion at least ground_other_min, the chosen one
  /// is an object filling the view and the world shows only on the ground: ambiguous.
  double ground_share = 0.05;
  double ground_depth = 0.3;  ///< [m]
  double ground_explained_max = 0.1;
  double ground_other_min = 0.5;
  /// [m/s^2] a hypothesis whose refined |gravity| is further than this from 9.81 is not chosen
  /// (it may still be a contender).
  double max_gravity_error = 3.0;
  /// [1/(m/s)^2] smallest eigenvalue of the velocity information of the chosen motion's
  /// inliers below which the directions do not constrain the velocity.
  double min_info_eigen = 100.0;
  int ransac_iterations = 64;
  int max_hypotheses = 3;
  /// [s] prior std of the LiDAR-IMU clock offset (LiDAR clock minus IMU clock) about zero: a
  /// moving start estimates it with the motion ([joint] time_offset_sigma; 0: the clocks are
  /// taken as synchronized).
  double time_offset_sigma = 0;
};

/// One Doppler return of the start span.
struct StartPoint {
  double t = 0;             ///< [s] from the window start
  Vec3 d_l = Vec3::Zero();  ///< unit direction in the LiDAR frame
  double doppler = 0;       ///< [m/s]
  double range = 0;         ///< [m] of the return (0: not known; the ground check skips it)
};

/// A motion the returns support.
struct StartHypothesis {
  Vec3 v_b0 = Vec3::Zero();  ///< [m/s] body velocity at the window start, in b0
  Vec3 g_b0 = Vec3::Zero();  ///< [m/s^2] gravity (minus the accelerometer bias) in b0
  /// Covariance of (v_b0, g_b0), the gyro-bias uncertainty marginalized.
  Eigen::Matrix<double, 6, 6> cov = Eigen::Matrix<double, 6, 6>::Identity();
  std::size_t inliers = 0;
  double coverage = 0;      ///< [0, 1] share of the occupied direction cells that support it
  double residual_rms = 0;  ///< [m/s] of the inliers
  /// [m/s] the Doppler noise the residuals show, robustly (1.4826 times their median absolute
  /// value among those within max(gate, 5 times that scale), iterated: a few tens of percent of
  /// returns on moving objects leave it), and the returns it rests on.
  double residual_scale = 0;
  std::size_t residual_scale_returns = 0;
  double min_info_eigen =
      0;              ///< [1/(m/s)^2] weakest direction of the inliers' velocity information
  bool rest = false;  ///< |v_b0| below max_speed
  /// |g_b0| within max_gravity_error of 9.81 m/s^2: only such a motion can be the platform's.
  bool plausible_gravity = true;
  /// [s] the LiDAR-IMU clock offset the motion was fitted with (LiDAR clock minus IMU clock) and
  /// its std (0: not estimated, the clocks taken as synchronized). v_b0 and g_b0 are at the IMU's
  /// time 0, cov has the offset's uncertainty marginalized.
  double time_offset = 0;
  double time_offset_sigma = 0;
};

struct StartDecision {
  enum class Kind {
    Moving,      ///< the platform moves: `chosen`
    Rest,        ///< the platform stands: `chosen` (v_b0 ~ 0)
    Ambiguous,   ///< the data cannot decide what moves (message says why)
    NoData,      ///< too few returns (message says why)
    Degenerate,  ///< the returns' directions do not constrain the velocity
  };
  Kind kind = Kind::NoData;
  std::string message;
  StartHypothesis chosen;
  std::vector<StartHypothesis> hypotheses;  ///< every refined hypothesis, best coverage first
  bool imu_still = false;  ///< the IMU shows only white noise over the span (imu_rest.still)
  /// What the span's IMU samples say about rest, whatever their noise level
  /// (detail::imuRestEvidence), and their first differences (the noise at rest).
  detail::ImuRestEvidence imu_rest;
};

/// The start decision's span of a window: its first IMU sample k_first (the first at or after
/// t_first, the window's first LiDAR return) and its last k_last, [start] duration later or the
/// last one inside the window. valid: k_first has a sample after it; complete: the samples given
/// cover the span (a later one exists, or k_last is the window's last).
struct StartSpan {
  std::size_t k_first = 0, k_last = 0;
  bool valid = false;
  bool complete = false;
};
StartSpan startSpan(const std::vector<ImuSample>& imu, double t_first, const FreeInitConfig& cfg);

/// The start decision's settings from the estimator's configuration ([doppler] noise and gate,
/// [imu] noises and gyro-bias prior, [start] rest speed and information floor).
StartDetectorParams startDetectorParams(const FreeInitConfig& cfg);

/// Decides the motion at the window start from the IMU samples `imu[k_first..k_last]` (times
/// absolute; imu[k_first].t is the window start) and the returns of [imu[k_first].t, imu[k_last].t]
/// (times relative to the window start, in time order: std::invalid_argument otherwise).
/// `b_g_prior` is removed from the gyro. A moving start with params.time_offset_sigma > 0 has the
/// clock offset fitted with its motion (StartHypothesis::time_offset); a motion whose gravity is
/// implausible with the clocks synchronized is tried again with the offset free. Deterministic.
/// `extra` (optional, per sample of `imu`): the IMU screen's synthetic samples, which the noise
/// at rest leaves out (detail::imuRestEvidence).
StartDecision decideStart(const std::vector<ImuSample>& imu, std::size_t k_first,
                          std::size_t k_last, const std::vector<StartPoint>& points,
                          const Extrinsics& extrinsics, const Vec3& b_g_prior,
                          const StartDetectorParams& params,
                          const std::vector<detail::ImuExtraNoise>* extra = nullptr);

}  // namespace freeinit
