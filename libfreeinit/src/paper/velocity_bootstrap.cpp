#include "paper/velocity_bootstrap.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace freeinit {

VelocityFitParams velocityFitParams(const FreeInitConfig& config) {
  VelocityFitParams p;
  p.iterations = config.paper_bootstrap.iterations;
  p.cauchy_scale = config.paper_bootstrap.cauchy_scale;
  p.prior_sigma = config.paper_bootstrap.prior_sigma;
  p.min_info_eigen = config.start.min_info_eigen;
  return p;
}

VelocityFit fitLidarVelocity(const std::vector<Vec3>& d_l, const std::vector<double>& doppler,
                             const VelocityFitParams& params, double doppler_sigma) {
  VelocityFit fit;
  const std::size_t n = std::min(d_l.size(), doppler.size());
  if (n < 10) {
    fit.message = "fewer than 10 Doppler returns";
    return fit;
  }
  const double inv_r = 1.0 / (doppler_sigma * doppler_sigma);
  const Mat3 prior_info = Mat3::Identity() / (params.prior_sigma * params.prior_sigma);
  std::vector<double> w(n, 1.0), abs_r(n);
  Vec3 v = Vec3::Zero();
  Mat3 A = Mat3::Zero();
  double scale = params.cauchy_scale;
  for (int it = 0; it <= params.iterations; ++it) {
    // Weighted normal equations of r_i = z_i + d_i^T v.
    A = prior_info;
    Vec3 b = Vec3::Zero();
    for (std::size_t i = 0; i < n; ++i) {
      A.noalias() += (w[i] * inv_r) * d_l[i] * d_l[i].transpose();
      b -= (w[i] * inv_r * doppler[i]) * d_l[i];
    }
    v = A.ldlt().solve(b);
    // Residuals; the scale follows the median absolute residual down to the Cauchy floor, so the
    // first (plain least-squares) pass cannot lock onto a wrong solution.
    for (std::size_t i = 0; i < n; ++i) abs_r[i] = std::abs(doppler[i] + d_l[i].dot(v));
    std::vector<double> tmp(abs_r);
    std::nth_element(tmp.begin(), tmp.begin() + n / 2, tmp.end());
    const double mad_sigma = 1.4826 * tmp[n / 2];
    scale = std::max(params.cauchy_scale, 2.0 * mad_sigma);
    for (std::size_t i = 0; i < n; ++i) {
      const double u = abs_r[i] / scale;
      w[i] = 1.0 / (1.0 + u * u);
    }
    fit.residual_sigma = mad_sigma;
  }
  Mat3 info = A - prior_info;
  const Eigen::SelfAdjointEigenSolver<Mat3> es(info);
  fit.min_info_eigen = es.eigenvalues()(0);
  fit.v_l = v;
  // Inflate by the observed residual spread when it exceeds the nominal Doppler noise.
  const double k = std::max(1.0, fit.residual_sigma / doppler_sigma);
  fit.cov = A.inverse() * k * k;
  fit.inliers = static_cast<std::size_t>(
      std::count_if(abs_r.begin(), abs_r.end(), [&](double r) { return r < 3 * scale; }));
  if (!v.allFinite()) {
    fit.message = "the velocity fit is not finite (invalid directions)";
    return fit;
  }
  if (!(fit.min_info_eigen >= params.min_info_eigen)) {
    fit.message = "the point directions do not constrain the velocity (weakest information " +
                  std::to_string(fit.min_info_eigen) + " < " +
                  std::to_string(params.min_info_eigen) + ")";
    return fit;
  }
  fit.ok = true;
  return fit;
}

}  // namespace freeinit
