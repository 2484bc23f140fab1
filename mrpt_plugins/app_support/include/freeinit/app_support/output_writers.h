// Writers of the app's outputs. Each file is written to "<path>.tmp" and renamed when complete,
// so every output is either complete or absent.
#pragma once

#include <freeinit/initial_state.h>
#include <freeinit/io/atomic_file.h>

#include <ostream>
#include <string>
#include <vector>

namespace freeinit::app_support {

/// The atomic writer (freeinit/io/atomic_file.h), under the name the glue has always used.
using freeinit::writeFileAtomically;

/// What a user without ground truth reads to judge a state: the 1-sigma of the main quantities
/// (from its covariance), the window it used, and the Doppler residuals against the configured
/// noise (a quantized sensor at rest legitimately shows residuals of zero).
struct StateVerdict {
  Vec3 sigma_v_b = Vec3::Zero();  ///< [m/s] body velocity, per axis
  double sigma_tilt_deg = 0;      ///< [deg] gravity direction (the angle's RMS, 2 dof)
  Vec3 sigma_b_g = Vec3::Zero();  ///< [rad/s]
  Vec3 sigma_b_a = Vec3::Zero();  ///< [m/s^2]
  double window_s = 0;            ///< [s] window start to state time
  std::size_t window_frames = 0;  ///< LiDAR frames with points in the window
  std::size_t points_used = 0;
  double residual_rms = 0;   ///< [m/s] of the used points' Doppler residuals
  double doppler_sigma = 0;  ///< [m/s] the configured Doppler noise
  /// Chi-square per dof of the returns per IMU sample against the noise model (0: not tested;
  /// Diagnostics::node_residual_ratio).
  double node_residual_ratio = 0;
  /// [s] InitialState::time_offset, its std and whether the data determined it.
  double time_offset = 0;
  double time_offset_sigma = 0;
  bool time_offset_estimated = false;
  /// The white noises the estimator used, their relative sigma, source and configured values
  /// (Diagnostics::noise).
  NoiseReport noise;
  /// IMU samples of the window rejected as faults (Diagnostics::imu_faults).
  std::size_t imu_faults = 0;
  double imu_gap_s = 0;  ///< [s] IMU gaps of the window bridged (Diagnostics::imu_gap_s)
};
/// The verdict of an ok result (doppler_sigma: the configured [doppler] doppler_sigma).
StateVerdict verdictOf(const InitResult& r, double doppler_sigma);
/// The verdict as console lines ("  sigma ...", "  window ...").
void printVerdict(std::ostream& log, const StateVerdict& v);

/// The initial-state contract (docs/architecture.md, "Frames, signs and the output contract"):
/// [initial_state] status, timestamp, q_wb, p_w, v_w, b_g, b_a, g_w, cov (18x18 row-major, order
/// [dtheta p v b_g b_a g]); for ok states time_offset (value [s], std [s], "estimated" or "prior":
/// InitialState::time_offset_estimated); with a verdict (ok states) also sigma_v_b, sigma_tilt_deg,
/// sigma_b_g, sigma_b_a, window_s, window_frames, points_used, doppler_residual_rms,
/// doppler_sigma, node_chi2_per_dof, imu_faults and imu_gap_s, and noise_gyro, noise_accel,
/// noise_doppler ("value rel_sigma source", the configured value in the comment); then warnings.
void writeInitialStateIni(const std::string& path, const InitialState& s,
                          const StateVerdict* verdict = nullptr);
/// TUM: "t x y z qx qy qz qw" per line.
void writeTum(const std::string& path, const std::vector<PoseSample>& trajectory);
/// The velocimeter's time series, CSV with a header line.
void writeVelocityCsv(const std::string& path, const std::vector<VelocitySample>& v);
/// Binary little-endian PLY with x y z intensity doppler time (float32; time from the state's
/// timestamp).
void writePly(const std::string& path, const std::vector<MapPoint>& points);

}  // namespace freeinit::app_support
