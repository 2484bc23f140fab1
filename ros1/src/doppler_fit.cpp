#include <freeinit/ros1/doppler_fit.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <random>

namespace freeinit::ros1 {
namespace {

struct Obs {
  Vec3 d;    // unit direction, sensor frame
  double z;  // Doppler [m/s]
  double t;  // time offset [s]
};

// Residual of the model doppler = -d^T v.
double residual(const Obs& o, const Vec3& v) { return o.z + o.d.dot(v); }

// MSAC cost: squared residuals truncated at the threshold.
double cost(const std::vector<Obs>& obs, const Vec3& v, double thr2) {
  double c = 0;
  for (const Obs& o : obs) c += std::min(thr2, residual(o, v) * residual(o, v));
  return c;
}

}  // namespace

DopplerFit fitScanVelocity(const std::vector<DopplerPoint>& points, const DopplerFitParams& p) {
  DopplerFit fit;
  std::vector<Obs> obs;
  obs.reserve(points.size());
  for (const DopplerPoint& pt : points) {
    const Vec3 x = pt.p_l.cast<double>();
    const double r = x.norm();
    if (!(r > 0) || r < p.min_range || !std::isfinite(r) || !std::isfinite(pt.doppler)) continue;
    obs.push_back({x / r, pt.doppler, pt.time_offset});
  }
  fit.points = obs.size();
  const std::size_t n = obs.size();
  if (n < std::max<std::size_t>(p.min_points, 4)) {
    fit.message = "only " + std::to_string(n) + " usable points (at least " +
                  std::to_string(std::max<std::size_t>(p.min_points, 4)) + ")";
    return fit;
  }
  const double thr2 = p.inlier_threshold * p.inlier_threshold;
  auto weakDirections = [&](const Mat3& DtD) {
    const double min_eigen = Eigen::SelfAdjointEigenSolver<Mat3>(DtD).eigenvalues()(0);
    if (min_eigen >= p.min_info_eigen) return false;
    fit.message = "the directions do not constrain every axis (smallest eigenvalue of D^T D " +
                  std::to_string(min_eigen) + " < " + std::to_string(p.min_info_eigen) + ")";
    return true;
  };
  {
    Mat3 all = Mat3::Zero();
    for (const Obs& o : obs) all.noalias() += o.d * o.d.transpose();
    if (weakDirections(all)) return fit;
  }

  // Hypotheses: exact solutions through 3 points.
  Vec3 best = Vec3::Zero();
  double best_cost = cost(obs, best, thr2);  // v = 0 is a hypothesis too (a sensor at rest)
  auto tryTriple = [&](std::size_t a, std::size_t b, std::size_t c) {
    Mat3 D;
    D << obs[a].d.transpose(), obs[b].d.transpose(), obs[c].d.transpose();
    if (std::abs(D.determinant()) < 1e-3) return;  // nearly coplanar directions
    const Vec3 v = D.lu().solve(-Vec3(obs[a].z, obs[b].z, obs[c].z));
    const double c2 = cost(obs, v, thr2);
    if (c2 < best_cost) {
      best_cost = c2;
      best = v;
    }
  };
  const double triples =
      static_cast<double>(n) * static_cast<double>(n - 1) * static_cast<double>(n - 2) / 6.0;
  if (triples <= p.hypotheses) {
    for (std::size_t a = 0; a < n; ++a)
      for (std::size_t b = a + 1; b < n; ++b)
        for (std::size_t c = b + 1; c < n; ++c) tryTriple(a, b, c);
  } else {
    std::mt19937 rng(p.seed);
    std::uniform_int_distribution<std::size_t> pick(0, n - 1);
    for (int h = 0; h < p.hypotheses; ++h) {
      const std::size_t a = pick(rng);
      std::size_t b = pick(rng), c = pick(rng);
      if (a == b || a == c || b == c) continue;
      tryTriple(a, b, c);
    }
  }

  // Least squares on the inliers until the set is stable.
  Vec3 v = best;
  std::vector<char> inlier(n, 0);
  Mat3 A = Mat3::Zero();
  std::size_t m = 0;
  for (int it = 0; it < 20; ++it) {
    std::vector<char> next(n, 0);
    for (std::size_t i = 0; i < n; ++i)
      next[i] = std::abs(residual(obs[i], v)) <= p.inlier_threshold;
    const bool stable = it > 0 && next == inlier;
    inlier = std::move(next);
    A.setZero();
    Vec3 b = Vec3::Zero();
    m = 0;
    for (std::size_t i = 0; i < n; ++i) {
      if (!inlier[i]) continue;
      A.noalias() += obs[i].d * obs[i].d.transpose();
      b -= obs[i].z * obs[i].d;
      ++m;
    }
    if (m < 4) break;
    if (stable) break;
    v = A.ldlt().solve(b);
  }
  fit.inliers = m;
  if (m < 4 || static_cast<double>(m) < p.min_inlier_fraction * static_cast<double>(n)) {
    fit.message = std::to_string(m) + " of " + std::to_string(n) +
                  " points agree on one velocity (at least " +
                  std::to_string(p.min_inlier_fraction) + " needed)";
    return fit;
  }
  if (weakDirections(A)) {
    fit.message = "inliers: " + fit.message;
    return fit;
  }
  double ss = 0, t_sum = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!inlier[i]) continue;
    ss += residual(obs[i], v) * residual(obs[i], v);
    t_sum += obs[i].t;
  }
  fit.residual_sigma = std::sqrt(ss / static_cast<double>(m - 3));
  const double s = std::max(fit.residual_sigma, p.sigma_floor);
  fit.v_l = v;
  fit.cov = s * s * A.inverse();
  fit.mean_time_offset = t_sum / static_cast<double>(m);
  fit.ok = v.allFinite() && fit.cov.allFinite();
  if (!fit.ok) fit.message = "the solution is not finite";
  return fit;
}

}  // namespace freeinit::ros1
