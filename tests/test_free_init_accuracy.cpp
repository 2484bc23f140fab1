// Free-Init against simulated ground truth on every preset of the paper's Table I (plus tunnels),
// three seeds each, default configuration and default LiDAR density (60,000 points per frame).
//
// Bounds are the targets. Where a quantity is not observable on a preset (the horizontal
// accelerometer bias at rest or driving straight; the gyro bias in a short moving window) the test
// checks the observable part and that the reported covariance covers the rest (NEES).
#include <freeinit/free_init.h>
#include <freeinit/sim/evaluation.h>
#include <freeinit/sim/simulator.h>
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "test_stats.h"

namespace freeinit {
namespace {

constexpr int kSeeds = 3;
const std::vector<std::string> kRotational = {"dyna_01", "dyna_02", "dyna_04"};
const std::vector<std::string> kStatic = {"stat_01", "stat_02", "stat_03", "stat_04"};
const std::vector<std::string> kDriving = {"dyna_05", "dyna_06", "tunnel_wheeled",
                                           "tunnel_vehicular"};

struct Outcome {
  sim::InitErrors err;
  InitResult result;
};

/// Runs one preset and seed; `gyro_prior_sigma` > 0 gives the estimator a gyro-bias prior as from
/// a static calibration (the truth plus noise of that std).
Outcome runPreset(const std::string& name, std::uint64_t seed, double gyro_prior_sigma = 0) {
  auto sc = sim::preset(name, seed);
  sc.duration = 0.7;  // the 0.5 s window plus margin
  const sim::Recording rec = sim::simulate(sc);
  FreeInitConfig cfg;
  cfg.extrinsics = rec.extrinsics;
  if (gyro_prior_sigma > 0) {
    std::mt19937_64 rng(777 + seed);
    std::normal_distribution<double> n01;
    cfg.imu.gyro_bias_prior = rec.b_g + gyro_prior_sigma * Vec3(n01(rng), n01(rng), n01(rng));
    cfg.imu.gyro_bias_sigma0 = gyro_prior_sigma;
  }
  Outcome o;
  o.result = FreeInit::run(cfg, rec.imu, rec.frames);
  o.err = sim::evaluate(o.result.state, rec);
  return o;
}

/// Results are computed once per (preset, seed, prior) and shared by the tests below.
const Outcome& outcome(const std::string& name, std::uint64_t seed, double gyro_prior = 0) {
  static std::map<std::tuple<std::string, std::uint64_t, double>, Outcome> cache;
  const auto key = std::make_tuple(name, seed, gyro_prior);
  auto it = cache.find(key);
  if (it == cache.end()) it = cache.emplace(key, runPreset(name, seed, gyro_prior)).first;
  return it->second;
}

std::string tag(const std::string& name, std::uint64_t seed) {
  return name + " seed " + std::to_string(seed);
}

TEST(FreeInitAccuracy, InitializesWithAValidCovarianceAndVelocityWithin5cmOnEveryPreset) {
  for (const auto& name : sim::presetNames()) {
    for (std::uint64_t s = 1; s <= kSeeds; ++s) {
      const Outcome& o = outcome(name, s);
      ASSERT_TRUE(o.result.state.ok()) << tag(name, s) << ": " << o.result.state.message;
      // The 18x18 covariance is a covariance: symmetric, positive semi-definite.
      const Cov18& P = o.result.state.cov;
      EXPECT_LT((P - P.transpose()).cwiseAbs().maxCoeff(), 1e-15) << tag(name, s);
      const Eigen::SelfAdjointEigenSolver<Cov18> es(P);
      EXPECT_GT(es.eigenvalues().minCoeff(), -1e-12 * es.eigenvalues().maxCoeff()) << tag(name, s);
      EXPECT_LE(o.err.vel_b, 0.05) << tag(name, s) << " |v| = " << o.err.vel_b_true_norm;
    }
  }
}

TEST(FreeInitAccuracy, GravityWithinHalfDegreeOnRotationalStarts) {
  for (const auto& name : kRotational)
    for (std::uint64_t s = 1; s <= kSeeds; ++s)
      EXPECT_LE(outcome(name, s).err.gravity_deg, 0.5) << tag(name, s);
}

// The accelerometer bias is observable through rotation. At 10 rad/s (dyna_04) all of it is
// within 0.05 m/s^2. At 5 rad/s (dyna_01, dyna_02) the axis the platform rotates about least is
// weakly observable within 0.5 s, and the reported covariance says so: along every direction the
// covariance calls observable (sigma <= 0.02 m/s^2) the error is within 0.05 m/s^2, and along the
// others within 4 sigma.
TEST(FreeInitAccuracy, AccelBiasWhereRotationMakesItObservable) {
  for (std::uint64_t s = 1; s <= kSeeds; ++s)
    EXPECT_LE(outcome("dyna_04", s).err.accel_bias, 0.05) << tag("dyna_04", s);
  for (const char* name : {"dyna_01", "dyna_02"}) {
    for (std::uint64_t s = 1; s <= kSeeds; ++s) {
      const Outcome& o = outcome(name, s);
      const Mat3 C = o.result.state.cov.block<3, 3>(kBa, kBa);
      const Eigen::SelfAdjointEigenSolver<Mat3> es(C);
      for (int i = 0; i < 3; ++i) {
        const double sigma = std::sqrt(es.eigenvalues()(i));
        const double e = std::abs(es.eigenvectors().col(i).dot(o.err.accel_bias_vector));
        if (sigma <= 0.02)
          EXPECT_LE(e, 0.05) << tag(name, s) << " observable direction " << i;
        else
          EXPECT_LE(e, 4 * sigma) << tag(name, s) << " weak direction " << i;
      }
    }
  }
}

// At rest the horizontal accelerometer bias is indistinguishable from a tilt: the gravity error
// may reach atan(|b_a,h| / g); the test allows 0.1 deg more. The vertical bias and the gyro bias
// are observable.
TEST(FreeInitAccuracy, StaticStarts) {
  for (const auto& name : kStatic) {
    for (std::uint64_t s = 1; s <= kSeeds; ++s) {
      const auto& e = outcome(name, s).err;
      EXPECT_TRUE(outcome(name, s).result.diag.static_start) << tag(name, s);
      EXPECT_LE(e.gravity_deg, e.gravity_deg_from_bias + 0.1) << tag(name, s);
      EXPECT_LE(e.gyro_bias, 0.002) << tag(name, s);
      EXPECT_LE(e.accel_bias_vertical, 0.01) << tag(name, s);
      EXPECT_LE(e.vel_b, 0.01) << tag(name, s);
    }
  }
}

// Driving straight, the gyro bias is not observable in 0.5 s and at 20 m/s a 0.02 rad/s bias looks
// like 0.4 m/s^2 of lateral acceleration; with a gyro-bias prior from a static calibration the
// gravity error is down to what the unobservable horizontal accelerometer bias implies, plus
// 0.2 deg: four times the rms (0.055 deg) of that remainder over the four driving presets and
// seeds 1-8 with every point. Without the prior this fails (dyna_05 seed 1: 1.50 deg, where
// the accelerometer bias implies 0.85).
TEST(FreeInitAccuracy, DrivingWithCalibratedGyroBias) {
  for (const auto& name : kDriving) {
    for (std::uint64_t s = 1; s <= kSeeds; ++s) {
      const auto& e = outcome(name, s, 0.0005).err;
      EXPECT_LE(e.gravity_deg, e.gravity_deg_from_bias + 0.2) << tag(name, s);
      EXPECT_LE(e.vel_b, 0.05) << tag(name, s);
      EXPECT_LE(e.accel_bias_vertical, 0.05) << tag(name, s);
    }
  }
}

// Consistency of the reported covariance: the NEES averaged over all presets and seeds, for each
// gauge-free quantity, lies within the two-sided 99.9% chi-square interval of its degrees of
// freedom (Wilson-Hilferty approximation of the chi-square quantiles).
using test::chi2Quantile;

TEST(FreeInitAccuracy, CovarianceIsConsistentOverPresetsAndSeeds) {
  double v = 0, tilt = 0, bg = 0, ba = 0;
  int n = 0, n_moving = 0;
  for (const auto& name : sim::presetNames()) {
    for (std::uint64_t s = 1; s <= kSeeds; ++s) {
      const auto& e = outcome(name, s).err;
      ASSERT_TRUE(e.valid) << tag(name, s);
      if (e.vel_b_true_norm > 0.01) {  // at rest the zero-velocity update is exact
        v += e.nees_vel_b;
        ++n_moving;
      }
      tilt += e.nees_tilt;
      bg += e.nees_gyro_bias;
      ba += e.nees_accel_bias;
      ++n;
    }
  }
  const auto check = [&](const char* what, double sum, int runs, double dof) {
    const double total_dof = runs * dof;
    EXPECT_GE(sum, chi2Quantile(total_dof, -3.29)) << what << " mean NEES " << sum / runs;
    EXPECT_LE(sum, chi2Quantile(total_dof, 3.29)) << what << " mean NEES " << sum / runs;
  };
  // The velocimeter's velocity covariance is deliberately conservative: its random walk must cover
  // the error of the accelerometer-aided propagation when the first gravity estimate is poor, and
  // where that estimate is good the velocity is better than the random walk says (mean NEES about
  // 1 for 3 dof). Never overconfident (upper bound), at most 4x conservative in variance.
  EXPECT_LE(v, chi2Quantile(n_moving * 3.0, 3.29)) << "body velocity mean NEES " << v / n_moving;
  EXPECT_GE(v, chi2Quantile(n_moving * 3.0, -3.29) / 4)
      << "body velocity mean NEES " << v / n_moving;
  check("tilt", tilt, n, 2);
  check("gyro bias", bg, n, 3);
  check("accel bias", ba, n, 3);
}

// The early smoothing (at 75 % of the window) leaves the final one (what an online user waits for)
// a few Gauss-Newton steps: one and its check as before, one more where the LiDAR-IMU clock offset
// (estimated by default) is still moving, and one re-solve where the Doppler noise read from the
// final residuals moved by more than 5 % (measured: at most 4 on every preset and seed). More would
// mean the early smoothing no longer converges the window; the closing call's cost itself is
// measured by the benchmarks.
TEST(FreeInitAccuracy, FinalSmoothingTakesAFewIterations) {
  for (const auto& name : sim::presetNames())
    for (int s = 1; s <= kSeeds; ++s)
      EXPECT_LE(outcome(name, s).result.diag.iterations, 4) << tag(name, s);
}

}  // namespace
}  // namespace freeinit
