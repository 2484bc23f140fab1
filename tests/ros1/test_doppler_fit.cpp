// The per-scan Doppler-only velocity fit against ground truth: simulated radar-like scans (40
// points over a 120 x 30 deg field of view, velocities of a hand-carried rig) with Gaussian noise,
// quantization and moving-object outliers. Seeded; tolerances from the injected noise.
#include <freeinit/ros1/doppler_fit.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace freeinit;
using namespace freeinit::ros1;

namespace {

struct Scan {
  std::vector<DopplerPoint> points;
  Vec3 v;
};

// n points at 1-15 m, azimuth +-60 deg, elevation +-15 deg around the sensor's x axis; Doppler =
// -d^T v + N(0, sigma), rounded to multiples of `step` (0: not), `outliers` of them replaced by a
// moving object's return (uniform in +-3 m/s).
Scan scan(std::mt19937& rng, std::size_t n, double sigma, double step, std::size_t outliers,
          const Vec3& v) {
  std::uniform_real_distribution<double> az(-M_PI / 3, M_PI / 3), el(-M_PI / 12, M_PI / 12),
      range(1, 15), wild(-3, 3);
  std::normal_distribution<double> noise(0, sigma);
  Scan s;
  s.v = v;
  for (std::size_t i = 0; i < n; ++i) {
    const double a = az(rng), e = el(rng);
    const Vec3 d(std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e));
    double z = -d.dot(v) + noise(rng);
    if (i < outliers) z = wild(rng);
    if (step > 0) z = step * std::round(z / step);
    DopplerPoint p;
    p.p_l = (range(rng) * d).cast<float>();
    p.doppler = static_cast<float>(z);
    p.time_offset = static_cast<float>(0.0185 * (i + 0.5) / n);
    s.points.push_back(p);
  }
  return s;
}

Vec3 handheldVelocity(std::mt19937& rng) {
  std::normal_distribution<double> g(0, 0.8);
  return Vec3(g(rng), g(rng), 0.3 * g(rng));
}

}  // namespace

// Noiseless: the exact velocity (to rounding of the float32 points and Doppler: 1e-6 m/s).
TEST(DopplerFit, NoiselessIsExact) {
  std::mt19937 rng(1);
  for (int trial = 0; trial < 20; ++trial) {
    const Scan s = scan(rng, 40, 0.0, 0.0, 0, handheldVelocity(rng));
    const DopplerFit f = fitScanVelocity(s.points, {});
    ASSERT_TRUE(f.ok) << f.message;
    EXPECT_LT((f.v_l - s.v).norm(), 1e-5) << trial;
    EXPECT_EQ(f.inliers, 40u);
    EXPECT_NEAR(f.mean_time_offset, 0.0185 / 2, 1e-9);  // float32 offsets
  }
}

// Gaussian noise and 25 % outliers: the covariance is consistent with the errors (mean NEES of
// 3-dof errors over 400 scans within 3 +- 0.5: its standard error is sqrt(6/400) = 0.12, and the
// residual std from ~30 inliers is itself uncertain by ~13 %, which the NEES absorbs), and no
// error beyond the chi-square 99.9 % bound in more than 2 % of the scans (an outlier can fall
// within the inlier band by chance).
TEST(DopplerFit, NoisyWithOutliersHasAConsistentCovariance) {
  std::mt19937 rng(2);
  double nees = 0;
  int beyond = 0;
  const int trials = 400;
  DopplerFitParams p;
  p.inlier_threshold = 0.15;
  for (int trial = 0; trial < trials; ++trial) {
    const Scan s = scan(rng, 40, 0.04, 0.0, 10, handheldVelocity(rng));
    const DopplerFit f = fitScanVelocity(s.points, p);
    ASSERT_TRUE(f.ok) << trial << ": " << f.message;
    const Vec3 e = f.v_l - s.v;
    const double q = e.dot(f.cov.inverse() * e);
    nees += q / trials;
    beyond += q > 16.27 ? 1 : 0;
    EXPECT_GE(f.inliers, 28u) << trial;  // 30 static points; few of them beyond 3.75 sigma
  }
  EXPECT_NEAR(nees, 3.0, 0.5);
  EXPECT_LE(beyond, trials / 50);
}

// Quantized Doppler (0.125 m/s bins, as the TI radar's) on top of 0.025 m/s of noise (what the
// recording's moving residuals, 0.044 m/s RMS, leave after the bins' 0.036): the rounding is then
// dithered and the covariance consistent (mean NEES within 3 +- 0.6 over 300 scans; with noise far
// below a bin the rounding errors follow the geometry and the NEES reaches 3.5-3.7, i.e. the
// sigmas are up to ~10 % optimistic). At rest (every Doppler exactly 0) the fit is exactly 0 and
// only the floor step/sqrt(12) gives it a covariance.
TEST(DopplerFit, QuantizedDopplerAndTheFloor) {
  std::mt19937 rng(3);
  const double step = 0.124919;
  DopplerFitParams p;
  p.sigma_floor = step / std::sqrt(12.0);
  double nees = 0;
  const int trials = 300;
  for (int trial = 0; trial < trials; ++trial) {
    const Scan s = scan(rng, 40, 0.025, step, 0, handheldVelocity(rng));
    const DopplerFit f = fitScanVelocity(s.points, p);
    ASSERT_TRUE(f.ok) << f.message;
    const Vec3 e = f.v_l - s.v;
    nees += e.dot(f.cov.inverse() * e) / trials;
  }
  EXPECT_NEAR(nees, 3.0, 0.6);

  const Scan rest = scan(rng, 40, 0.0, step, 0, Vec3::Zero());
  const DopplerFit f = fitScanVelocity(rest.points, p);
  ASSERT_TRUE(f.ok) << f.message;
  EXPECT_EQ(f.v_l, Vec3::Zero());
  EXPECT_EQ(f.residual_sigma, 0.0);
  EXPECT_GT(f.cov.diagonal().minCoeff(), 0.0);
  // Without the floor a zero residual would claim a perfect velocity.
  p.sigma_floor = 0;
  EXPECT_EQ(fitScanVelocity(rest.points, p).cov.diagonal().maxCoeff(), 0.0);
}

// Degenerate scans say so instead of returning a confident velocity: too few points, directions
// all in one plane (the velocity across it is unobserved), mostly disagreeing points.
TEST(DopplerFit, DegenerateScansAreNotFitted) {
  std::mt19937 rng(4);
  const Scan few = scan(rng, 6, 0.02, 0.0, 0, Vec3(1, 0, 0));
  EXPECT_FALSE(fitScanVelocity(few.points, {}).ok);

  Scan flat = scan(rng, 40, 0.02, 0.0, 0, Vec3(1, 0.2, 0.1));
  for (auto& pt : flat.points) pt.p_l.z() = 0;  // every direction in the x-y plane
  const DopplerFit f = fitScanVelocity(flat.points, {});
  EXPECT_FALSE(f.ok);
  EXPECT_NE(f.message.find("do not constrain"), std::string::npos) << f.message;

  const Scan wild = scan(rng, 40, 0.02, 0.0, 30, Vec3(1, 0, 0));
  const DopplerFit w = fitScanVelocity(wild.points, {});
  EXPECT_FALSE(w.ok);
  EXPECT_NE(w.message.find("agree on one velocity"), std::string::npos) << w.message;
}

// Points too close or not finite are not used; an empty scan is no fit.
TEST(DopplerFit, UnusablePointsAreSkipped) {
  std::mt19937 rng(5);
  Scan s = scan(rng, 40, 0.0, 0.0, 0, Vec3(0.5, -0.5, 0.1));
  s.points[0].p_l.setZero();
  s.points[1].doppler = std::nanf("");
  s.points[2].p_l = Eigen::Vector3f(0.2f, 0, 0);
  DopplerFitParams p;
  p.min_range = 0.5;
  const DopplerFit f = fitScanVelocity(s.points, p);
  ASSERT_TRUE(f.ok) << f.message;
  EXPECT_EQ(f.points, 37u);
  EXPECT_LT((f.v_l - s.v).norm(), 1e-5);
  EXPECT_FALSE(fitScanVelocity({}, p).ok);
}
