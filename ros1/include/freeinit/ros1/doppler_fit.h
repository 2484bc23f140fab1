// The sensor velocity of one scan from its points' Doppler alone: no IMU, no other scan, no
// estimator state. An independent reference for the velocity the estimator reports, and a
// per-scan baseline.
//
// For a static point at unit direction d (sensor frame), doppler = -d^T v_l (freeinit/types.h).
// The fit is MSAC (RANSAC scored by the truncated squared residual) over 3-point solutions, then
// least squares on the inliers (|residual| <= inlier_threshold), repeated until the inlier set is
// stable. Covariance: s^2 (D^T D)^-1 over the inliers, s^2 their residual variance (n - 3 degrees
// of freedom), never below sigma_floor^2. Quantized Doppler (a radar's velocity bins) makes
// every residual exactly zero at rest; the floor is then the quantization noise, step / sqrt(12).
// (With noise far below a bin the rounding errors follow the geometry instead of averaging out,
// and the covariance is up to ~10 % optimistic in sigma; a moving radar's noise dithers them.)
//
// Deterministic: the hypotheses come from a seeded generator (all triples for small scans).
#pragma once

#include <freeinit/types.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace freeinit::ros1 {

struct DopplerFitParams {
  double min_range = 0.0;            ///< [m] closer points are not used
  double inlier_threshold = 0.15;    ///< [m/s] largest |residual| of an inlier
  double sigma_floor = 0.0;          ///< [m/s] lower bound of the per-point residual std
  int hypotheses = 400;              ///< 3-point hypotheses (all triples when there are fewer)
  std::size_t min_points = 8;        ///< fewer usable points: no fit
  double min_inlier_fraction = 0.5;  ///< fewer inliers: no fit (mostly moving objects or noise)
  /// [-] smallest eigenvalue of D^T D over the inliers (D: rows d^T); below it the directions do
  /// not constrain every velocity axis (the weakest axis' sigma is then above 3x the residual
  /// std). A radar's narrow elevation gives 0.2-2 with 40 points.
  double min_info_eigen = 0.1;
  std::uint32_t seed = 1;
};

struct DopplerFit {
  bool ok = false;
  std::string message;      ///< why not, when !ok
  Vec3 v_l = Vec3::Zero();  ///< [m/s] sensor velocity, sensor frame
  Mat3 cov = Mat3::Zero();  ///< [(m/s)^2]
  std::size_t points = 0;   ///< points used (within range, finite)
  std::size_t inliers = 0;
  double residual_sigma = 0;    ///< [m/s] std of the inlier residuals (before the floor)
  double mean_time_offset = 0;  ///< [s] mean time offset of the inliers: the time v_l refers to
};

/// Fits the sensor velocity to `points` (their p_l and doppler). Never throws on data.
DopplerFit fitScanVelocity(const std::vector<DopplerPoint>& points, const DopplerFitParams& params);

}  // namespace freeinit::ros1
