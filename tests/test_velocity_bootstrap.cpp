// Robust LiDAR velocity from Doppler returns (IRLS, Cauchy): accuracy with gross outliers, high
// speed, degenerate geometries, too few points, covariance consistency.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <random>
#include <vector>

#include "paper/velocity_bootstrap.h"
#include "test_stats.h"

namespace freeinit {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Two-sided 0.999 bounds of chi-square(300): the sum of 100 independent 3-dof NEES values of a
// consistent estimator falls outside with probability 1e-3.
const double kChi2_300_Lo = test::chi2Quantile(300, -3.29);
const double kChi2_300_Hi = test::chi2Quantile(300, 3.29);
using test::randomUnit;

/// Directions of a spinning LiDAR: full azimuth, elevation within +-15 deg.
Vec3 lidarDirection(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> az(-kPi, kPi), el(-15.0 * kPi / 180, 15.0 * kPi / 180);
  const double a = az(rng), e = el(rng);
  return Vec3(std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e));
}

struct Scan {
  std::vector<Vec3> d;
  std::vector<double> doppler;
  std::vector<bool> outlier;
};

/// sigma^2 (sum over inliers of d d^T)^-1: the least-squares covariance an oracle that knew the
/// inliers would reach (the "N_eff" of the accuracy bounds).
Mat3 oracleCovariance(const Scan& s, double sigma) {
  Mat3 info = Mat3::Zero();
  for (std::size_t i = 0; i < s.d.size(); ++i)
    if (!s.outlier[i]) info += s.d[i] * s.d[i].transpose();
  return sigma * sigma * info.inverse();
}

TEST(VelocityBootstrap, RecoversVelocityWithTenPercentGrossOutliers) {
  // 2000 points on the sphere, sigma = 0.03 m/s, 10% gross outliers of 1..10 m/s of either sign.
  // Per axis the oracle std is ~0.03 sqrt(3/1800) ~ 1.2e-3 m/s; the Cauchy weights
  // (scale 0.1 m/s) leave each outlier an influence w r ~ 0.01 / r, a residual bias ~1e-4 m/s.
  // Asserted: each axis within 5 oracle sigmas; the inlier count is exact (inliers are within
  // 10 sigma = 0.3 m/s = 3 Cauchy scales, outliers beyond 1 m/s).
  const VelocityFitParams params;
  const double sigma = 0.03;
  const Vec3 v_true(3.0, -1.0, 0.5);
  for (int seed = 0; seed < 10; ++seed) {
    std::mt19937_64 rng(500 + seed);
    std::normal_distribution<double> noise(0.0, sigma);
    std::uniform_real_distribution<double> unif(0.0, 1.0), gross(1.0, 10.0);
    Scan s;
    std::size_t n_in = 0;
    for (int i = 0; i < 2000; ++i) {
      const Vec3 d = randomUnit(rng);
      const bool out = (i % 10 == 3);
      double z = -d.dot(v_true) + noise(rng);
      if (out) z += (unif(rng) < 0.5 ? -1 : 1) * gross(rng);
      n_in += out ? 0 : 1;
      s.d.push_back(d);
      s.doppler.push_back(z);
      s.outlier.push_back(out);
    }
    const VelocityFit fit = fitLidarVelocity(s.d, s.doppler, params, sigma);
    ASSERT_TRUE(fit.ok) << fit.message;
    const Mat3 C = oracleCovariance(s, sigma);
    for (int k = 0; k < 3; ++k) EXPECT_LT(std::abs(fit.v_l(k) - v_true(k)), 5 * std::sqrt(C(k, k)));
    EXPECT_EQ(fit.inliers, n_in);
    // The robust residual spread estimates sigma (MAD inflated by the 10% outliers: ~1.13 sigma).
    EXPECT_GT(fit.residual_sigma, 0.8 * sigma);
    EXPECT_LT(fit.residual_sigma, 1.4 * sigma);
  }
}

TEST(VelocityBootstrap, HighSpeedWithDynamicObjectConverges) {
  // 21 m/s (75 km/h) seen by a spinning LiDAR (+-15 deg elevation, so z is the weak axis), 2000
  // points, sigma = 0.03, and a moving vehicle: 10% of the points, a contiguous azimuth sector,
  // all with the same +8 m/s Doppler offset (a one-sided outlier set that biases the first,
  // plain least-squares pass). Each axis within 5 oracle sigmas (the vehicle's residual pull
  // after reweighting is ~200 * 0.1^2 / 8 / 600 ~ 4e-4 m/s, below one sigma).
  const VelocityFitParams params;
  const double sigma = 0.03;
  const Vec3 v_true(19.5, -7.0, 2.5);
  ASSERT_NEAR(v_true.norm(), 20.9, 0.1);
  std::mt19937_64 rng(77);
  std::normal_distribution<double> noise(0.0, sigma);
  Scan s;
  for (int i = 0; i < 2000; ++i) {
    Vec3 d = lidarDirection(rng);
    const bool out = i < 200;
    if (out) {  // the vehicle: azimuth in [0.5, 0.8] rad
      const double a = 0.5 + 0.3 * i / 200.0;
      d = Vec3(std::cos(a), std::sin(a), 0.05).normalized();
    }
    s.d.push_back(d);
    s.doppler.push_back(-d.dot(v_true) + noise(rng) + (out ? 8.0 : 0.0));
    s.outlier.push_back(out);
  }
  const VelocityFit fit = fitLidarVelocity(s.d, s.doppler, params, sigma);
  ASSERT_TRUE(fit.ok) << fit.message;
  const Mat3 C = oracleCovariance(s, sigma);
  for (int k = 0; k < 3; ++k)
    EXPECT_LT(std::abs(fit.v_l(k) - v_true(k)), 5 * std::sqrt(C(k, k))) << "axis " << k;
  EXPECT_EQ(fit.inliers, 1800u);
}

TEST(VelocityBootstrap, DegenerateDirectionsAreRejected) {
  // Noise-free Doppler, so only the geometry can make the fit fail.
  const VelocityFitParams params;
  const Vec3 v_true(1.0, 2.0, 3.0);
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> az(-kPi, kPi);
  // All directions in the horizontal plane: v_z is unobservable.
  std::vector<Vec3> planar;
  std::vector<double> z_planar;
  for (int i = 0; i < 500; ++i) {
    const double a = az(rng);
    planar.emplace_back(std::cos(a), std::sin(a), 0.0);
    z_planar.push_back(-planar.back().dot(v_true));
  }
  const VelocityFit fp = fitLidarVelocity(planar, z_planar, params, 0.03);
  EXPECT_FALSE(fp.ok);
  EXPECT_FALSE(fp.message.empty());
  EXPECT_LT(fp.min_info_eigen, params.min_info_eigen);
  // One direction only: two axes unobservable.
  const Vec3 d = Vec3(0.6, 0.0, 0.8);
  const std::vector<Vec3> same(500, d);
  const std::vector<double> z_same(500, -d.dot(v_true));
  const VelocityFit fs = fitLidarVelocity(same, z_same, params, 0.03);
  EXPECT_FALSE(fs.ok);
  EXPECT_FALSE(fs.message.empty());
  // Control: the same number of well-spread directions is accepted.
  std::vector<Vec3> spread;
  std::vector<double> z_spread;
  for (int i = 0; i < 500; ++i) {
    spread.push_back(randomUnit(rng));
    z_spread.push_back(-spread.back().dot(v_true));
  }
  EXPECT_TRUE(fitLidarVelocity(spread, z_spread, params, 0.03).ok);
}

TEST(VelocityBootstrap, TooFewPointsFail) {
  const VelocityFitParams params;
  const double sigma = 0.03;
  const Vec3 v_true(1.0, -2.0, 0.5);
  // Ten axis-like, well-spread directions.
  std::vector<Vec3> d = {Vec3(1, 0, 0),  Vec3(0, 1, 0),  Vec3(0, 0, 1), Vec3(-1, 0, 0),
                         Vec3(0, -1, 0), Vec3(0, 0, -1), Vec3(1, 1, 1), Vec3(-1, 1, 0),
                         Vec3(0, -1, 1), Vec3(1, 0, -1)};
  for (auto& x : d) x.normalize();
  std::vector<double> z;
  for (const auto& x : d) z.push_back(-x.dot(v_true));
  const VelocityFit nine =
      fitLidarVelocity(std::vector<Vec3>(d.begin(), d.begin() + 9),
                       std::vector<double>(z.begin(), z.begin() + 9), params, sigma);
  EXPECT_FALSE(nine.ok);
  EXPECT_FALSE(nine.message.empty());
  EXPECT_FALSE(fitLidarVelocity({}, {}, params, sigma).ok);
  // Ten noise-free points suffice. Expected: the ridge solution with the weak prior
  // (info_prior = 1/40^2), (H^T H / s^2 + I / 40^2)^-1 H^T z / s^2; the Cauchy weights are
  // 1 - O(1e-12) for residuals of ~1e-7 m/s.
  const VelocityFit ten = fitLidarVelocity(d, z, params, sigma);
  ASSERT_TRUE(ten.ok) << ten.message;
  Mat3 A = Mat3::Identity() / (params.prior_sigma * params.prior_sigma);
  Vec3 b = Vec3::Zero();
  for (std::size_t i = 0; i < d.size(); ++i) {
    A += d[i] * d[i].transpose() / (sigma * sigma);
    b -= d[i] * z[i] / (sigma * sigma);
  }
  EXPECT_LT((ten.v_l - A.ldlt().solve(b)).norm(), 1e-9);
  EXPECT_LT((ten.v_l - v_true).norm(), 1e-5);  // the prior's pull: ~|v| 6e-4 / 3700 ~ 4e-7
}

TEST(VelocityBootstrap, CovarianceIsConsistentOverSeeds) {
  // 100 seeds x 500 LiDAR-like points, Gaussian noise only: the NEES sum must fall in the
  // chi-square(300) two-sided 0.999 interval. (The Cauchy weights ~0.92 at 0.3 scales and the
  // MAD inflation make the reported covariance a few % conservative, well inside the interval;
  // a covariance off by a factor of 2 either way is not.)
  const VelocityFitParams params;
  const double sigma = 0.03;
  const Vec3 v_true(5.0, 1.0, -0.3);
  double nees = 0;
  for (int seed = 0; seed < 100; ++seed) {
    std::mt19937_64 rng(3000 + seed);
    std::normal_distribution<double> noise(0.0, sigma);
    std::vector<Vec3> d;
    std::vector<double> z;
    for (int i = 0; i < 500; ++i) {
      d.push_back(lidarDirection(rng));
      z.push_back(-d.back().dot(v_true) + noise(rng));
    }
    const VelocityFit fit = fitLidarVelocity(d, z, params, sigma);
    ASSERT_TRUE(fit.ok) << fit.message;
    const Vec3 e = fit.v_l - v_true;
    nees += e.dot(fit.cov.ldlt().solve(e));
  }
  EXPECT_GT(nees, kChi2_300_Lo);
  EXPECT_LT(nees, kChi2_300_Hi);
}

}  // namespace
}  // namespace freeinit
