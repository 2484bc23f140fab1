// The Doppler-inertial velocimeter (paper Sec. III-B): observation models and their Jacobians vs
// finite differences (checked through the Kalman update the class performs), closed-form
// convergence and covariance consistency, the gyro and zero-velocity updates, gating, numerical
// health of the covariance, and continuous-time process noise.
#include <freeinit/rotation.h>
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <random>
#include <utility>

#include "paper/velocimeter.h"
#include "test_stats.h"

namespace freeinit {
namespace {

using Vec9 = Eigen::Matrix<double, 9, 1>;
using Mat9 = Eigen::Matrix<double, 9, 9>;
using Row9 = Eigen::Matrix<double, 1, 9>;
using Mat6 = Eigen::Matrix<double, 6, 6>;

// Two-sided 0.999 bounds of chi-square(300): the sum of 100 independent 3-dof NEES values of a
// consistent estimator falls outside with probability 1e-3.
const double kChi2_300_Lo = test::chi2Quantile(300, -3.29);
const double kChi2_300_Hi = test::chi2Quantile(300, 3.29);
using test::randomUnit;

Vec3 randomNormal(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Vec3(n(rng), n(rng), n(rng));
}

/// A LiDAR point at a random direction and range, and its direction d_l = p_l / |p_l| as the
/// velocimeter computes it from the float position. The coordinates are first rounded to a 2^-16 m
/// grid: with |p| < 64 m they fit in 22 bits, so the float conversion is exact. (Converting a
/// double to float and back in one function is not safe here: GCC 12.2 at -O2 vectorizes
/// `float f = x; double y = f;` into y = x, dropping the rounding, which made d_l differ from the
/// library's by ~1e-8.)
struct Ray {
  Eigen::Vector3f p_l;
  Vec3 d_l;
};
Ray randomRay(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> range(2.0, 60.0);
  const Vec3 p = (randomUnit(rng) * range(rng) * 65536.0).array().round() / 65536.0;
  Ray ray;
  ray.p_l = p.cast<float>();
  ray.d_l = p.normalized();
  return ray;
}

// Observation models written from the paper, independently of the library.
// Body model (Eq. (doppler_vel_obs) with v_l = R_lb (v_b + omega_b x p_bl)):
//   h_b(x) = -(R_bl d)^T (v_b + omega_b x p_bl),  x = [v_b, omega_b, b_g].
double dopplerBody(const Vec9& x, const Vec3& d_l, const Mat3& R_bl, const Vec3& p_bl) {
  return -(R_bl * d_l).dot(x.segment<3>(0) + x.segment<3>(3).cross(p_bl));
}
// LiDAR model: h_l(v_l) = -d^T v_l.
double dopplerLidar(const Vec3& v_l, const Vec3& d_l) { return -d_l.dot(v_l); }

/// Central-difference Jacobian of a scalar function. The models are linear, so the truncation
/// error is zero and only rounding remains: ~eps |h| / step.
template <int N, typename F>
Eigen::Matrix<double, 1, N> numericJacobian(const F& f, const Eigen::Matrix<double, N, 1>& x) {
  constexpr double kStep = 1e-4;
  Eigen::Matrix<double, 1, N> J;
  for (int i = 0; i < N; ++i) {
    Eigen::Matrix<double, N, 1> xp = x, xm = x;
    xp(i) += kStep;
    xm(i) -= kStep;
    J(i) = (f(xp) - f(xm)) / (2 * kStep);
  }
  return J;
}

Vec9 bodyState(const Velocimeter& velocimeter) {
  Vec9 x;
  x << velocimeter.v_b(), velocimeter.omega_b(), velocimeter.b_g();
  return x;
}

double maxAbs(const Eigen::MatrixXd& m) { return m.cwiseAbs().maxCoeff(); }

// -------------------------------------------------------------------------------------------------
// Observation models and Jacobians.

TEST(Velocimeter, DopplerJacobiansMatchFiniteDifferences) {
  // The H rows the update must use: body [-u^T, (u x p_bl)^T, 0] with u = R_bl d, LiDAR [-d^T].
  std::mt19937_64 rng(11);
  for (int i = 0; i < 200; ++i) {
    const Mat3 R_bl = Exp(Vec3(randomNormal(rng)));
    const Vec3 p_bl = 0.5 * randomNormal(rng);
    const Vec3 d = randomUnit(rng);
    Vec9 x;
    x << 10.0 * randomNormal(rng), 3.0 * randomNormal(rng), 0.05 * randomNormal(rng);
    const Vec3 u = R_bl * d;
    Row9 H_analytic;
    H_analytic << -u.transpose(), u.cross(p_bl).transpose(), 0, 0, 0;
    const Row9 H_num =
        numericJacobian<9>([&](const Vec9& y) { return dopplerBody(y, d, R_bl, p_bl); }, x);
    // Rounding only: eps * |h| (~30 m/s) / step (1e-4) ~ 1e-10.
    EXPECT_LT((H_num - H_analytic).norm(), 1e-9);
    const Vec3 v_l = 10.0 * randomNormal(rng);
    const Eigen::RowVector3d Hl_num =
        numericJacobian<3>([&](const Vec3& y) { return dopplerLidar(y, d); }, v_l);
    EXPECT_LT((Hl_num + d.transpose()).norm(), 1e-9);
    // Both models give the same Doppler for a rigid body: v_b = R_bl v_l - omega_b x p_bl.
    Vec9 x_rigid = x;
    x_rigid.segment<3>(0) = R_bl * v_l - x.segment<3>(3).cross(p_bl);
    EXPECT_NEAR(dopplerBody(x_rigid, d, R_bl, p_bl), dopplerLidar(v_l, d), 1e-12 * 100);
  }
}

/// One Doppler update from a random filter state (start()) compared with a Kalman update built
/// from the finite-difference Jacobians of the models above: innovation, state and covariance
/// (Joseph form, an algebra independent of the library's). `full`: the paper's update of all
/// states; otherwise the Schmidt update where omega_b and b_g are consider states.
void checkDopplerUpdateAgainstNumericKalman(bool full, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  for (int i = 0; i < 200; ++i) {
    VelocimeterParams params;
    params.doppler_updates_omega = full;
    params.doppler_sigma = 0.05;
    // Large omega/bias uncertainty so the lever-arm columns of H carry weight in the gain.
    params.gyro_sigma = 0.2;
    params.gyro_bias_sigma0 = 0.3;
    params.gyro_bias_prior = 0.1 * randomNormal(rng);
    Extrinsics ext;
    ext.R_bl = Exp(Vec3(randomNormal(rng)));
    ext.p_bl = 0.5 * randomNormal(rng);
    Velocimeter velocimeter(params, ext);
    Mat3 A;
    A << randomNormal(rng), randomNormal(rng), randomNormal(rng);
    const Mat3 P_l0 = A * A.transpose() + 0.1 * Mat3::Identity();
    const Vec3 v_l0 = 5.0 * randomNormal(rng);
    velocimeter.start(1.0, v_l0, P_l0, 2.0 * randomNormal(rng));

    const Vec9 x0 = bodyState(velocimeter);
    const Mat9 P0 = velocimeter.covBody();
    // A true rigid-body state half a sigma away from the estimate (innovation well inside the
    // 4-sigma gate): body errors drawn from P0, the LiDAR velocity from the rigid-body relation.
    Vec9 n9;
    for (int k = 0; k < 9; ++k) n9(k) = std::normal_distribution<double>(0.0, 1.0)(rng);
    const Vec9 x_true = x0 + 0.5 * Mat9(P0.llt().matrixL()) * n9;
    const Vec3 v_l_true =
        ext.R_bl.transpose() * (x_true.segment<3>(0) + x_true.segment<3>(3).cross(ext.p_bl));
    const Ray ray = randomRay(rng);
    const double z = dopplerLidar(v_l_true, ray.d_l);
    ASSERT_NEAR(z, dopplerBody(x_true, ray.d_l, ext.R_bl, ext.p_bl), 1e-9);

    const auto out = velocimeter.updateDoppler(ray.p_l, z);
    ASSERT_TRUE(out.accepted);

    // Body block.
    const auto hb = [&](const Vec9& y) { return dopplerBody(y, ray.d_l, ext.R_bl, ext.p_bl); };
    const Row9 H = numericJacobian<9>(hb, x0);
    const double r = params.doppler_sigma * params.doppler_sigma;
    // Innovation = h(x_true) - h(x0) = H (x_true - x0) exactly (linear model).
    const double innov = z - hb(x0);
    EXPECT_NEAR(out.residual, innov, 1e-9 * (1 + std::abs(innov)));
    EXPECT_NEAR(out.residual, H.dot(x_true - x0), 1e-8 * (1 + std::abs(innov)));
    const double S = H * P0 * H.transpose() + r;
    Vec9 K = P0 * H.transpose() / S;
    Mat9 E = Mat9::Identity();  // which states the update corrects
    if (!full) {
      K.tail<6>().setZero();
      E.bottomRightCorner<6, 6>().setZero();
    }
    const Vec9 x1 = x0 + K * innov;
    const Mat9 M = Mat9::Identity() - K * H;
    const Mat9 P1 = M * P0 * M.transpose() + K * r * K.transpose();
    EXPECT_LT((bodyState(velocimeter) - x1).norm(), 1e-9 * (1 + x1.norm()));
    EXPECT_LT(maxAbs(velocimeter.covBody() - P1), 1e-10 * maxAbs(P0));
    if (!full) {
      // Consider states: estimates and their own covariance block untouched.
      EXPECT_EQ(velocimeter.omega_b(), x0.segment<3>(3));
      EXPECT_EQ(velocimeter.b_g(), x0.segment<3>(6));
      EXPECT_EQ(Mat6(velocimeter.covBody().bottomRightCorner<6, 6>()),
                Mat6(P0.bottomRightCorner<6, 6>()));
    }

    // LiDAR block.
    const auto hl = [&](const Vec3& y) { return dopplerLidar(y, ray.d_l); };
    const Eigen::RowVector3d Hl = numericJacobian<3>(hl, v_l0);
    const double S_l = Hl * P_l0 * Hl.transpose() + r;
    const Vec3 K_l = P_l0 * Hl.transpose() / S_l;
    const Vec3 v_l1 = v_l0 + K_l * (z - hl(v_l0));
    const Mat3 M_l = Mat3::Identity() - K_l * Hl;
    const Mat3 P_l1 = M_l * P_l0 * M_l.transpose() + K_l * r * K_l.transpose();
    EXPECT_LT((velocimeter.v_l() - v_l1).norm(), 1e-9 * (1 + v_l1.norm()));
    EXPECT_LT(maxAbs(velocimeter.covVl() - P_l1), 1e-10 * maxAbs(P_l0));
  }
}

TEST(Velocimeter, FullDopplerUpdateIsKalmanWithNumericJacobian) {
  checkDopplerUpdateAgainstNumericKalman(true, 21);
}

TEST(Velocimeter, SchmidtDopplerUpdateIsKalmanWithNumericJacobian) {
  checkDopplerUpdateAgainstNumericKalman(false, 22);
}

// -------------------------------------------------------------------------------------------------
// Convergence and consistency, constant velocity, no rotation.

struct ConstantVelocityCase {
  Mat3 R_bl = Exp(Vec3(0.3, -0.2, 0.5));
  Vec3 p_bl = Vec3(0.25, -0.1, 0.15);
  Vec3 v_l_true = Vec3(4.0, -1.5, 0.7);  // [m/s]
};

TEST(Velocimeter, NoiseFreeConstantVelocityConverges) {
  // All points at one instant (no propagation): the filter is recursive least squares. With exact
  // Doppler the only error left is the prior's pull, (P0^-1 + I_N)^-1 P0^-1 e0 with information
  // I_N ~ N/(3 sigma^2) per axis: 1e-2 / (2000 / (3 * 9e-4)) * 4.4 m/s ~ 6e-8 m/s.
  const ConstantVelocityCase c;
  VelocimeterParams params;
  Extrinsics ext{c.R_bl, c.p_bl};
  Velocimeter velocimeter(params, ext);
  velocimeter.start(0.0, Vec3::Zero(), 100.0 * Mat3::Identity(), Vec3::Zero());
  std::mt19937_64 rng(1);
  for (int i = 0; i < 2000; ++i) {
    const Ray ray = randomRay(rng);
    const auto out = velocimeter.updateDoppler(ray.p_l, dopplerLidar(c.v_l_true, ray.d_l));
    ASSERT_TRUE(out.accepted) << "point " << i;
  }
  EXPECT_LT((velocimeter.v_l() - c.v_l_true).norm(), 1e-6);
  // No rotation: v_b = R_bl v_l.
  EXPECT_LT((velocimeter.v_b() - c.R_bl * c.v_l_true).norm(), 1e-6);
}

TEST(Velocimeter, NoisyConstantVelocityIsConsistent) {
  // 100 seeds x 1000 points, Doppler noise sigma = 0.03 m/s. Each seed draws its own consistent
  // prior: v_l0 ~ N(v_true, P_l0), a true gyro bias ~ N(0, sigma_b0^2) and the first gyro sample
  // with its noise, so that the start() covariance is the true error covariance. omega_true = 0.
  // Checks per seed: the LiDAR covariance equals the recursive-least-squares one,
  // (P_l0^-1 + sum d d^T / sigma^2)^-1, and each axis error is within 5 sigma of it
  // (sigma ~ 0.03 sqrt(3/1000) ~ 1e-3 m/s). Over seeds: the NEES of v_l and of v_b (whose error
  // is dominated by the consider states omega_b, b_g through the lever arm) sum to a
  // chi-square(300) value inside its two-sided 0.999 bounds.
  const ConstantVelocityCase c;
  VelocimeterParams params;  // sigma 0.03, gyro_sigma 0.002, sigma_b0 0.015
  const Extrinsics ext{c.R_bl, c.p_bl};
  const double sigma = params.doppler_sigma;
  const Mat3 P_l0 = Mat3::Identity() * 4.0;  // 2 m/s per axis
  double nees_l = 0, nees_b = 0;
  for (int seed = 0; seed < 100; ++seed) {
    std::mt19937_64 rng(1000 + seed);
    std::normal_distribution<double> noise(0.0, sigma);
    Velocimeter velocimeter(params, ext);
    const Vec3 b_true = params.gyro_bias_sigma0 * randomNormal(rng);
    const Vec3 gyro0 = b_true + params.gyro_sigma * randomNormal(rng);
    velocimeter.start(0.0, c.v_l_true + 2.0 * randomNormal(rng), P_l0, gyro0);
    Mat3 info = P_l0.inverse();
    for (int i = 0; i < 1000; ++i) {
      const Ray ray = randomRay(rng);
      velocimeter.updateDoppler(ray.p_l, dopplerLidar(c.v_l_true, ray.d_l) + noise(rng));
      info += ray.d_l * ray.d_l.transpose() / (sigma * sigma);
    }
    const Mat3 cov_rls = info.inverse();
    // Each rank-1 downdate subtracts terms of the size of the prior (4 (m/s)^2) to reach
    // ~1e-6: rounding ~eps * 4 per update, 1000 updates -> < 1e-12 absolute (~1e-6 relative).
    EXPECT_LT(maxAbs(velocimeter.covVl() - cov_rls), 1e-12);
    const Vec3 e_l = velocimeter.v_l() - c.v_l_true;
    for (int k = 0; k < 3; ++k) EXPECT_LT(std::abs(e_l(k)), 5.0 * std::sqrt(cov_rls(k, k)));
    nees_l += e_l.dot(velocimeter.covVl().inverse() * e_l);
    const Vec3 e_b = velocimeter.v_b() - c.R_bl * c.v_l_true;
    nees_b += e_b.dot(velocimeter.covVb().inverse() * e_b);
  }
  EXPECT_GT(nees_l, kChi2_300_Lo);
  EXPECT_LT(nees_l, kChi2_300_Hi);
  EXPECT_GT(nees_b, kChi2_300_Lo);
  EXPECT_LT(nees_b, kChi2_300_Hi);
}

// -------------------------------------------------------------------------------------------------
// Gyro and zero-velocity updates.

TEST(Velocimeter, NoiseFreeGyroIsMatchedBySumOfRateAndBias) {
  // Constant omega, known bias (prior = truth, sigma 1e-4), noise-free gyro at 200 Hz, filter
  // started with a wrong first sample (omega_b = 0). The gyro observes omega_b + b_g; the update
  // leaves r_gyro / S of the residual, and the omega random walk makes S >= q_w dt = 5e-3, so each
  // update shrinks it by <= 4e-6 / 5e-3 = 8e-4. The only thing re-opening it is the Gauss-Markov
  // decay of b_g, |b| dt / tau ~ 1e-7 per step, leaving ~1e-10 after the update.
  VelocimeterParams params;
  const Vec3 omega_true(0.8, -1.2, 2.0), b_true(0.01, -0.02, 0.005);
  params.gyro_bias_prior = b_true;
  params.gyro_bias_sigma0 = 1e-4;
  Extrinsics ext;
  ext.p_bl = Vec3(0.1, 0.05, -0.2);
  Velocimeter velocimeter(params, ext);
  velocimeter.start(0.0, Vec3::Zero(), Mat3::Identity(), Vec3::Zero());
  const Vec3 gyro = omega_true + b_true;
  const double dt = 0.005;
  for (int k = 1; k <= 200; ++k) {
    velocimeter.propagate(k * dt);
    velocimeter.updateGyro(gyro, gyro, dt);
    if (k >= 5) {
      ASSERT_LT((velocimeter.omega_b() + velocimeter.b_g() - gyro).norm(), 1e-9) << "sample " << k;
    }
  }
  // The split follows the bias prior: b_g only drifts by the modelled decay, T/tau |b| ~ 2e-5.
  const double T = 200 * dt;
  EXPECT_LT((velocimeter.b_g() - b_true).norm(), 2.0 * T / params.gyro_bias_tau * b_true.norm());
  EXPECT_LT((velocimeter.omega_b() - omega_true).norm(),
            2.0 * T / params.gyro_bias_tau * b_true.norm());
}

TEST(Velocimeter, ZeroVelocityUpdateEstimatesGyroBiasAtRest) {
  // At rest omega = 0, so with the zero-velocity update each gyro sample is one independent
  // measurement of the bias: b_est ~ mean of n samples, error std sigma_g / sqrt(n) =
  // 0.002 / 10 = 2e-4 rad/s for n = 100 (the omega random walk, q_w dt = 1e-2 >> sigma^2, makes
  // each sample count afresh). Per axis the error stays below 5 sigma_g / sqrt(n) = 1e-3 rad/s.
  // The filter treats the pseudo-measurement omega = 0 as noisy (zupt sigma 0.002), so it should
  // report var(b) ~ (sigma_g^2 + sigma_z^2) / n plus the bias random walk accumulated over the
  // window (q_b T = 1e-8 against 8e-8): between 1.0 and 1.3 times (sigma_g^2 + sigma_z^2) / n.
  VelocimeterParams params;
  const double sigma_g = params.gyro_sigma, sigma_z = 0.002;
  const int n = 100;
  const double dt = 0.01;
  const double sigma_mean = sigma_g / std::sqrt(n);
  const double var_model = (sigma_g * sigma_g + sigma_z * sigma_z) / n;
  for (int seed = 0; seed < 20; ++seed) {
    std::mt19937_64 rng(200 + seed);
    Extrinsics ext;
    ext.p_bl = Vec3(0.1, 0.05, -0.2);
    Velocimeter velocimeter(params, ext);
    const Vec3 b_true = params.gyro_bias_sigma0 * randomNormal(rng);
    std::vector<Vec3> gyro(n);
    for (auto& g : gyro) g = b_true + sigma_g * randomNormal(rng);
    velocimeter.start(0.0, Vec3::Zero(), Mat3::Identity() * 1e-2, gyro[0]);
    for (int k = 0; k < n; ++k) {
      velocimeter.propagate(k * dt);
      velocimeter.updateZeroVelocity(sigma_z);
      const bool has_next = k + 1 < n;
      velocimeter.updateGyro(gyro[k], has_next ? gyro[k + 1] : gyro[k], has_next ? dt : 0.0);
    }
    const Vec3 e = velocimeter.b_g() - b_true;
    for (int k = 0; k < 3; ++k) {
      EXPECT_LT(std::abs(e(k)), 5.0 * sigma_mean) << "seed " << seed << " axis " << k;
      EXPECT_GT(velocimeter.covBg()(k, k), 1.0 * var_model);
      EXPECT_LT(velocimeter.covBg()(k, k), 1.3 * var_model);
    }
    EXPECT_LT(velocimeter.omega_b().norm(), 5.0 * sigma_z);
  }
}

// -------------------------------------------------------------------------------------------------
// Gating.

TEST(Velocimeter, GateRejectsInconsistentPointWithoutTouchingTheState) {
  const ConstantVelocityCase c;
  VelocimeterParams params;
  Velocimeter velocimeter(params, Extrinsics{c.R_bl, c.p_bl});
  velocimeter.start(0.0, Vec3::Zero(), 100.0 * Mat3::Identity(), Vec3::Zero());
  std::mt19937_64 rng(3);
  std::normal_distribution<double> noise(0.0, params.doppler_sigma);
  for (int i = 0; i < 2000; ++i) {
    const Ray ray = randomRay(rng);
    velocimeter.updateDoppler(ray.p_l, dopplerLidar(c.v_l_true, ray.d_l) + noise(rng));
  }
  // Converged: the gate is max(0.15, 4 sqrt(S)) + 0.01 |v_l| ~ 0.2 m/s, far below 5 m/s.
  const Vec3 v_l = velocimeter.v_l(), v_b = velocimeter.v_b(), omega = velocimeter.omega_b(),
             b_g = velocimeter.b_g();
  const Mat3 P_l = velocimeter.covVl();
  const Mat9 P_b = velocimeter.covBody();
  for (int i = 0; i < 100; ++i) {
    const Ray ray = randomRay(rng);
    const double sign = (i % 2 == 0) ? 1.0 : -1.0;
    const auto out =
        velocimeter.updateDoppler(ray.p_l, dopplerLidar(c.v_l_true, ray.d_l) + sign * 5.0);
    EXPECT_FALSE(out.accepted);
    EXPECT_NEAR(out.residual, sign * 5.0, 0.05);  // the innovation is reported anyway
  }
  EXPECT_EQ(velocimeter.v_l(), v_l);
  EXPECT_EQ(velocimeter.v_b(), v_b);
  EXPECT_EQ(velocimeter.omega_b(), omega);
  EXPECT_EQ(velocimeter.b_g(), b_g);
  EXPECT_EQ(velocimeter.covVl(), P_l);
  EXPECT_EQ(velocimeter.covBody(), P_b);
  // A consistent (noise-free) point is accepted and changes the state.
  const Ray ray = randomRay(rng);
  const auto out = velocimeter.updateDoppler(ray.p_l, dopplerLidar(c.v_l_true, ray.d_l));
  EXPECT_TRUE(out.accepted);
  EXPECT_NE(velocimeter.covVl(), P_l);
}

// -------------------------------------------------------------------------------------------------
// Numerical health and process noise.

struct CovarianceHealth {
  double max_rel_asym = 0;   ///< max |P - P^T| / max|P| at the time of the check
  double max_hist_asym = 0;  ///< max |P - P^T| / (largest max|P| seen so far)
  double min_eig = 1e300;    ///< smallest eigenvalue seen
  bool finite = true;
};

/// 1e5 Doppler updates at 100 kHz over a rotating, accelerating motion with 5% gross outliers,
/// 200 Hz gyro, kinematic propagation, an aided phase, a zero-velocity phase and its release.
/// Both covariance blocks are checked every 1000 points, half-way between two gyro updates (which
/// re-symmetrize P_b, so checking right after one would hide the Doppler and transition steps).
CovarianceHealth runRandomUpdates(bool full, std::uint64_t seed) {
  VelocimeterParams params;
  params.doppler_updates_omega = full;
  const Extrinsics ext{Exp(Vec3(0.1, 0.2, -0.3)), Vec3(0.3, -0.2, 0.1)};
  Velocimeter velocimeter(params, ext);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unif(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 1.0);
  velocimeter.start(0.0, Vec3(1, 0, 0), Mat3::Identity(), Vec3(0.1, 0.2, 0.3));
  CovarianceHealth h;
  double scale_b = maxAbs(velocimeter.covBody()), scale_l = maxAbs(velocimeter.covVl());
  for (int i = 1; i <= 100000; ++i) {
    const double t = i * 1e-5;
    const Vec3 v_l_true(5 * std::sin(3 * t), 2 * std::cos(2 * t), 0.5 * t);
    const Vec3 omega_true(2 * std::sin(5 * t), -1.5 * std::cos(4 * t), 3 * std::sin(t));
    velocimeter.propagate(t);
    const Ray ray = randomRay(rng);
    double z = dopplerLidar(v_l_true, ray.d_l) + params.doppler_sigma * noise(rng);
    if (unif(rng) < 0.05) z += 10.0 * (unif(rng) - 0.5);
    velocimeter.updateDoppler(ray.p_l, z);
    if (i % 500 == 0) {
      const Vec3 g = omega_true + Vec3(0.01, -0.01, 0.02) + params.gyro_sigma * randomNormal(rng);
      velocimeter.updateGyro(g, g, 5e-3);
    }
    if (i == 20000) velocimeter.setAcceleration(Vec3(0.5, -0.2, 0.1), Vec3::Zero());
    if (i >= 40000 && i < 45000 && i % 500 == 0) velocimeter.updateZeroVelocity(0.002);
    if (i == 45000) velocimeter.releaseZeroVelocity(0.5, 0.5);
    scale_b = std::max(scale_b, maxAbs(velocimeter.covBody()));
    scale_l = std::max(scale_l, maxAbs(velocimeter.covVl()));
    if (i % 1000 == 250) {
      const Eigen::MatrixXd Pb = velocimeter.covBody(), Pl = velocimeter.covVl();
      for (const auto& [P, scale] : {std::pair{Pb, scale_b}, std::pair{Pl, scale_l}}) {
        const double asym = maxAbs(P - P.transpose());
        h.max_rel_asym = std::max(h.max_rel_asym, asym / maxAbs(P));
        h.max_hist_asym = std::max(h.max_hist_asym, asym / scale);
        const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(P);
        h.min_eig = std::min(h.min_eig, es.eigenvalues()(0));
      }
    }
  }
  h.finite = velocimeter.v_l().allFinite() && velocimeter.v_b().allFinite() &&
             velocimeter.covBody().allFinite();
  return h;
}

TEST(Velocimeter, CovarianceStaysPositiveDefinite) {
  // Positive definite throughout, and symmetric to rounding: every asymmetric rounding error is
  // committed at the scale P had when it was made (eps ~ 1e-16 times the largest P seen, over
  // ~1e3 operations between re-symmetrizations), hence < 1e-12 of that scale. An update that
  // forgot a transposed block would leave asymmetries of the size of the update itself.
  for (const bool full : {true, false}) {
    const CovarianceHealth h = runRandomUpdates(full, full ? 41 : 42);
    EXPECT_GT(h.min_eig, 0.0) << (full ? "full" : "Schmidt");
    EXPECT_LT(h.max_hist_asym, 1e-12) << (full ? "full" : "Schmidt");
    EXPECT_TRUE(h.finite);
  }
}

// The covariance stays symmetric relative to its current scale: the transition F P F^T is
// re-symmetrized (the Doppler downdates are exactly symmetric and would otherwise keep its rounding
// asymmetry while P_l contracts ~1e5-fold, reaching ~3e-12 of the matrix).
TEST(Velocimeter, CovarianceStaysSymmetricRelativeToItsCurrentScale) {
  for (const bool full : {true, false}) {
    const CovarianceHealth h = runRandomUpdates(full, full ? 41 : 42);
    EXPECT_LT(h.max_rel_asym, 1e-12) << (full ? "full" : "Schmidt");
  }
}

TEST(Velocimeter, ProcessNoiseIsContinuousTime) {
  // With kinematic_propagation off and the Gauss-Markov decay made negligible (tau = 1e12 s,
  // dt/tau ~ 1e-13), the transition is the identity and P(t + T) = P(t) + Q T whatever the
  // number of steps. One step of 0.2 s vs 100 steps of 2 ms: both equal the closed form to
  // rounding (100 additions, ~1e-14 relative; 1e-12 asserted). A per-step Q would differ 100x.
  VelocimeterParams params;
  params.kinematic_propagation = false;
  params.gyro_bias_tau = 1e12;
  const Extrinsics ext{Exp(Vec3(0.2, 0.1, -0.4)), Vec3(0.3, 0.1, -0.2)};
  Velocimeter one(params, ext), many(params, ext);
  Mat3 A;
  A << 1.0, 0.2, -0.1, 0.0, 0.5, 0.3, 0.1, 0.0, 0.8;
  const Mat3 P_l0 = A * A.transpose();
  one.start(5.0, Vec3(2, -1, 0.5), P_l0, Vec3(0.3, -0.2, 1.0));
  many.start(5.0, Vec3(2, -1, 0.5), P_l0, Vec3(0.3, -0.2, 1.0));
  const Mat9 P_b0 = one.covBody();
  const double T = 0.2;
  one.propagate(5.0 + T);
  for (int k = 1; k <= 100; ++k) many.propagate(5.0 + T * k / 100.0);
  ASSERT_DOUBLE_EQ(many.time(), one.time());

  Mat9 Q = Mat9::Zero();
  Q.diagonal() << Vec3::Constant(params.vel_random_walk * params.vel_random_walk),
      Vec3::Constant(params.omega_random_walk * params.omega_random_walk),
      Vec3::Constant(params.gyro_bias_random_walk * params.gyro_bias_random_walk);
  const Mat9 P_b_expected = P_b0 + Q * T;
  const Mat3 P_l_expected =
      P_l0 + Mat3::Identity() * params.vel_random_walk * params.vel_random_walk * T;
  const double tol_b = 1e-12 * maxAbs(P_b_expected), tol_l = 1e-12 * maxAbs(P_l_expected);
  EXPECT_LT(maxAbs(one.covBody() - many.covBody()), tol_b);
  EXPECT_LT(maxAbs(one.covVl() - many.covVl()), tol_l);
  EXPECT_LT(maxAbs(one.covBody() - P_b_expected), tol_b);
  EXPECT_LT(maxAbs(many.covBody() - P_b_expected), tol_b);
  EXPECT_LT(maxAbs(one.covVl() - P_l_expected), tol_l);
  EXPECT_LT(maxAbs(many.covVl() - P_l_expected), tol_l);
  // Without kinematics the nominal velocities do not move.
  EXPECT_EQ(one.v_l(), many.v_l());
  EXPECT_EQ(one.v_b(), many.v_b());
}

}  // namespace
}  // namespace freeinit
