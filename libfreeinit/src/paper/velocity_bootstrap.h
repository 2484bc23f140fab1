// Robust LiDAR velocity from a set of Doppler returns, assuming one velocity for all of them:
// iteratively reweighted least squares (Cauchy) on doppler = -d^T v_l, with a conditioning check.
// Used to start the velocimeter, by its motion check at rest and by the per-frame Doppler
// baseline.
#pragma once

#include <freeinit/config.h>
#include <freeinit/types.h>

#include <string>
#include <vector>

namespace freeinit {

/// Settings of the robust fit ([paper_bootstrap], [start] min_info_eigen; see
/// velocityFitParams()). Defaults: those of FreeInitConfig.
struct VelocityFitParams {
  int iterations = 10;            ///< IRLS iterations
  double cauchy_scale = 0.1;      ///< [m/s] IRLS Cauchy scale
  double prior_sigma = 40.0;      ///< [m/s] weak prior on each velocity axis
  double min_info_eigen = 100.0;  ///< [1/(m/s)^2] below: not ok (degenerate geometry)
};

/// The fit's settings from the configuration.
VelocityFitParams velocityFitParams(const FreeInitConfig& config);

struct VelocityFit {
  bool ok = false;
  std::string message;          ///< reason when !ok
  Vec3 v_l = Vec3::Zero();      ///< [m/s]
  Mat3 cov = Mat3::Identity();  ///< [(m/s)^2]
  double min_info_eigen = 0;    ///< [1/(m/s)^2] weakest direction of the information matrix
  std::size_t inliers = 0;      ///< points with a residual below 3 Cauchy scales
  double residual_sigma = 0;    ///< [m/s] robust std of the inlier residuals
};

/// Fits v_l to unit directions `d_l` and Doppler values (same length).
/// Fails (ok = false) with fewer than 10 points or a weakest information direction below
/// params.min_info_eigen.
VelocityFit fitLidarVelocity(const std::vector<Vec3>& d_l, const std::vector<double>& doppler,
                             const VelocityFitParams& params, double doppler_sigma);

}  // namespace freeinit
