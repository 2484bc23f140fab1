// The Cramer-Rao bound: the aggregated computation against a dense per-point batch (isotropic and
// per-axis IMU noise), the exact sqrt(2) of twice the data, a closed form at rest, unobservable
// quantities, the zero-rate gyro-bias bound, and the simulator's side (which points of a recording
// it uses, its true noise).
#include <freeinit/eval/cramer_rao_bound.h>
#include <freeinit/rotation.h>
#include <freeinit/sim/analytic_trajectory.h>
#include <freeinit/sim/evaluation.h>
#include <freeinit/sim/presets.h>
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <random>

#include "bound_trajectories.h"
#include "test_stats.h"

namespace freeinit::eval {
namespace {

const Vec3 kG(0, 0, -kGravity);
using test::movingTrajectory;

std::vector<KinematicTruth> nodesOf(const sim::Trajectory& traj, double t0, int intervals,
                                    double rate) {
  std::vector<KinematicTruth> nodes;
  for (int k = 0; k <= intervals; ++k) {
    const double t = t0 + k / rate;
    const sim::TruthState s = traj.at(t);
    nodes.push_back({t, s.R_wb, s.v_w, s.a_w, s.omega_b});
  }
  return nodes;
}

struct Point {
  double t;
  Vec3 d_l;
};

/// Points at random times in [t0, t1] with random directions in a 120x60 deg field of view.
std::vector<Point> randomPoints(std::size_t n, double t0, double t1, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<Point> pts(n);
  for (auto& p : pts) {
    p.t = t0 + (t1 - t0) * u(rng);
    const double az = (u(rng) - 0.5) * 2.1, el = (u(rng) - 0.5) * 1.05;
    p.d_l = Vec3(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  }
  return pts;
}

BoundModel rigModel() {
  BoundModel m;
  m.extrinsics.R_bl = Exp(Vec3(0.3, -0.5, 1.0));
  m.extrinsics.p_bl = Vec3(0.08, -0.05, 0.12);
  return m;
}

/// max |A - B| relative to the scale sqrt(B_ii B_jj) of each entry.
double covarianceError(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B) {
  double e = 0;
  for (Eigen::Index i = 0; i < B.rows(); ++i)
    for (Eigen::Index j = 0; j < B.cols(); ++j)
      e = std::max(e, std::abs(A(i, j) - B(i, j)) / std::sqrt(B(i, i) * B(j, j)));
  return e;
}

TEST(CramerRaoBound, TwiceEveryPointShrinksEverySigmaBySqrt2) {
  // Moving, exact IMU, no bias priors, no random walk: the information is the points' alone, and
  // every bound is finite (the motion makes both biases and the tilt observable).
  BoundModel model = rigModel();
  model.gyro_sigma = model.accel_sigma = 0;
  const auto traj = movingTrajectory();
  const auto nodes = nodesOf(traj, 0.2, 60, 200.0);
  const auto pts = randomPoints(3000, nodes.front().t, nodes.back().t, 7);
  CramerRaoBound once(model, nodes), twice(model, nodes);
  for (const Point& p : pts) {
    once.addDoppler(p.t, p.d_l);
    twice.addDoppler(p.t, p.d_l);
    twice.addDoppler(p.t, p.d_l);
  }
  const Bound a = once.compute(), b = twice.compute();
  ASSERT_TRUE(a.ok && b.ok);
  EXPECT_EQ(a.measurements, 3000u);
  EXPECT_EQ(b.measurements, 6000u);
  for (const double x : {a.velocity, a.gravity_deg, a.gyro_bias, a.accel_bias})
    EXPECT_TRUE(std::isfinite(x) && x > 0) << x;
  EXPECT_NEAR(a.velocity / b.velocity, std::sqrt(2.0), 1e-9 * std::sqrt(2.0));
  EXPECT_NEAR(a.gravity_deg / b.gravity_deg, std::sqrt(2.0), 1e-9 * std::sqrt(2.0));
  EXPECT_NEAR(a.gyro_bias / b.gyro_bias, std::sqrt(2.0), 1e-9 * std::sqrt(2.0));
  EXPECT_NEAR(a.accel_bias / b.accel_bias, std::sqrt(2.0), 1e-9 * std::sqrt(2.0));
  EXPECT_LT(covarianceError(2 * b.cov, a.cov), 1e-9);
}

/// The aggregated bound against a dense per-point batch, for IMU noise of these per-axis scales.
void expectEqualToADenseBatch(const Vec3& gyro_axis_scale, const Vec3& accel_axis_scale) {
  // Every unknown explicit: the first state, each interval's IMU noise and bias random walks; one
  // row per point; the yaw fixed at the window start; solved densely. IMU noise, bias priors and
  // random walks on, with a lever arm and rotated extrinsics.
  BoundModel model = rigModel();
  model.gyro_bias_prior_sigma = 0.01;
  model.accel_bias_prior_sigma = 0.1;
  model.gyro_bias_random_walk = 1e-3;
  model.accel_bias_random_walk = 2e-2;
  model.gyro_axis_scale = gyro_axis_scale;
  model.accel_axis_scale = accel_axis_scale;
  const auto traj = movingTrajectory();
  const int K = 20;
  const auto nodes = nodesOf(traj, 0.5, K, 200.0);
  const auto pts = randomPoints(300, nodes.front().t, nodes.back().t, 11);
  CramerRaoBound bound(model, nodes);
  for (const Point& p : pts) ASSERT_TRUE(bound.addDoppler(p.t, p.d_l));
  const Bound agg = bound.compute();
  ASSERT_TRUE(agg.ok);

  // theta = [x_0 (12), then per interval k: n_g, n_a, w_g, w_a (12)].
  const int n = 12 + 12 * K;
  auto noiseCol = [](int k) { return 12 + 12 * k; };
  std::vector<Eigen::MatrixXd> Psi(K + 1);  // x_k = Psi_k theta
  Psi[0] = Eigen::MatrixXd::Zero(12, n);
  Psi[0].leftCols(12).setIdentity();
  for (int k = 0; k < K; ++k) {
    const Mat12x18& T = bound.transition(static_cast<std::size_t>(k));
    Psi[k + 1] = T.leftCols<12>() * Psi[k];
    Psi[k + 1].middleCols(noiseCol(k), 6) += T.rightCols<6>();
    Psi[k + 1].block(kDBg, noiseCol(k) + 6, 6, 6) += Eigen::MatrixXd::Identity(6, 6);
  }
  Eigen::MatrixXd info = Eigen::MatrixXd::Zero(n, n);
  const double w = 1.0 / (model.doppler_sigma * model.doppler_sigma);
  for (const Point& p : pts) {
    std::size_t k = 0;
    while (k + 1 < bound.intervals() && p.t >= nodes[k + 1].t) ++k;
    const Eigen::Matrix<double, 1, 18> r = bound.dopplerRow(k, p.t, p.d_l);
    Eigen::RowVectorXd row = r.leftCols<12>() * Psi[k];
    row.segment(noiseCol(static_cast<int>(k)), 6) += r.rightCols<6>();
    info += w * row.transpose() * row;
  }
  info.block<3, 3>(kDBg, kDBg) += Mat3::Identity() / std::pow(model.gyro_bias_prior_sigma, 2);
  info.block<3, 3>(kDBa, kDBa) += Mat3::Identity() / std::pow(model.accel_bias_prior_sigma, 2);
  for (int k = 0; k < K; ++k) {
    const double h = nodes[k + 1].t - nodes[k].t;
    // Per axis: sample noise sigma_i = sigma * scale_i, random walks isotropic.
    const Vec3 var[4] = {
        (model.gyro_sigma * gyro_axis_scale).cwiseAbs2(),
        (model.accel_sigma * accel_axis_scale).cwiseAbs2(),
        Vec3::Constant(model.gyro_bias_random_walk * model.gyro_bias_random_walk * h),
        Vec3::Constant(model.accel_bias_random_walk * model.accel_bias_random_walk * h)};
    for (int i = 0; i < 4; ++i)
      for (int a = 0; a < 3; ++a)
        info(noiseCol(k) + 3 * i + a, noiseCol(k) + 3 * i + a) += 1.0 / var[i](a);
  }
  // The yaw of the first attitude about the vertical: any weight fixes the gauge.
  Eigen::RowVectorXd yaw0 = Eigen::RowVectorXd::Zero(n);
  yaw0.segment<3>(kDTheta) = (nodes[0].R_wb.transpose() * -kG.normalized()).transpose();
  info += yaw0.transpose() * yaw0;
  const Eigen::MatrixXd A = bound.outputJacobian() * Psi[K];
  const Eigen::MatrixXd dense = A * info.ldlt().solve(A.transpose());
  EXPECT_LT(covarianceError(agg.cov, dense), 1e-10) << "aggregated\n"
                                                    << agg.cov << "\ndense\n"
                                                    << dense;
}

TEST(CramerRaoBound, EqualsADensePerPointBatch) {
  expectEqualToADenseBatch(Vec3::Ones(), Vec3::Ones());
}

// A unit whose axes differ in noise (the simulator draws each axis at 0.8-1.2 of the datasheet):
// the bound weights each axis' noise by its own variance.
TEST(CramerRaoBound, EqualsADensePerPointBatchWithPerAxisNoise) {
  expectEqualToADenseBatch(Vec3(0.8, 1.15, 1.2), Vec3(1.2, 0.85, 0.9));
}

TEST(CramerRaoBound, PerAxisNoiseIsWhatTheModelSaysItIs) {
  // Scales all equal to k are the isotropic noise k sigma; different scales give another bound.
  const auto traj = movingTrajectory();
  const auto nodes = nodesOf(traj, 0.2, 40, 200.0);
  const auto pts = randomPoints(2000, nodes.front().t, nodes.back().t, 5);
  auto boundOf = [&](const BoundModel& m) {
    CramerRaoBound b(m, nodes);
    for (const Point& p : pts) b.addDoppler(p.t, p.d_l);
    return b.compute();
  };
  BoundModel scaled = rigModel(), plain = rigModel(), uneven = rigModel();
  scaled.gyro_axis_scale = Vec3::Constant(1.3);
  scaled.accel_axis_scale = Vec3::Constant(0.7);
  plain.gyro_sigma *= 1.3;
  plain.accel_sigma *= 0.7;
  uneven.gyro_axis_scale = Vec3(0.8, 1.0, 1.2);
  EXPECT_EQ(scaled.gyroSigmaPerAxis(), Vec3::Constant(1.3 * scaled.gyro_sigma));
  const Bound a = boundOf(scaled), b = boundOf(plain), c = boundOf(rigModel()), d = boundOf(uneven);
  ASSERT_TRUE(a.ok && b.ok && c.ok && d.ok);
  EXPECT_LT(covarianceError(a.cov, b.cov), 1e-12);
  EXPECT_GT(covarianceError(d.cov, c.cov), 1e-4);
  BoundModel bad = rigModel();
  bad.gyro_axis_scale = Vec3(1, 0, 1);
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  bad = rigModel();
  bad.accel_axis_scale = Vec3(1, 1, std::nan(""));
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

/// Static, level body; LiDAR frame = body frame (no lever arm); exact IMU; points along the axes.
struct StaticCase {
  double sigma_bg = 0.01, sigma_ba = 0.1;
  std::vector<KinematicTruth> nodes;
  std::vector<Point> pts;
  StaticCase(double sbg, double sba) : sigma_bg(sbg), sigma_ba(sba) {
    for (int k = 0; k <= 100; ++k)
      nodes.push_back(
          {100.0 + k * 0.005, Mat3::Identity(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()});
    for (int i = 0; i < 600; ++i) {
      const double t = 100.0 + 0.5 * (i + 0.5) / 600.0;
      const int axis = i % 3;
      pts.push_back({t, (i % 2 ? 1.0 : -1.0) * Vec3::Unit(axis)});
    }
  }
  Bound bound() const {
    BoundModel m;
    m.gyro_sigma = m.accel_sigma = 0;
    m.gyro_bias_prior_sigma = sigma_bg;
    m.accel_bias_prior_sigma = sigma_ba;
    CramerRaoBound b(m, nodes);
    for (const Point& p : pts) b.addDoppler(p.t, p.d_l);
    return b.compute();
  }
};

TEST(CramerRaoBound, AtRestMatchesTheClosedForm) {
  // At rest, level, exact IMU: dtheta(t) = dtheta_0 - t db_g and
  //   dv_x(t) = dv_x0 + g (dtheta_y0 t - db_gy t^2/2) - db_ax t,
  //   dv_y(t) = dv_y0 - g (dtheta_x0 t - db_gx t^2/2) - db_ay t,   dv_z(t) = dv_z0 - db_az t,
  // and a point along +-e_i measures dv_i(t) with sigma. Each horizontal axis is a regression on
  // (dv_0, dtheta_0, db_g, db_a) with the bias priors; the vertical one on (dv_z0, db_az); the
  // yaw-rate bias keeps its prior.
  const StaticCase c(0.01, 0.1);
  const Bound b = c.bound();
  ASSERT_TRUE(b.ok);
  const double g = kGravity, T = 0.5, w = 1.0 / (0.03 * 0.03);
  auto horizontal = [&](int axis, double sign, double& var_v, double& var_th, double& var_bg,
                        double& var_ba) {
    Eigen::Matrix4d L = Eigen::Matrix4d::Zero();
    for (const Point& p : c.pts) {
      if (std::abs(p.d_l(axis)) < 0.5) continue;
      const double t = p.t - 100.0;
      const Eigen::Vector4d phi(1, sign * g * t, -sign * g * t * t / 2, -t);
      L += w * phi * phi.transpose();
    }
    L(2, 2) += 1 / (c.sigma_bg * c.sigma_bg);
    L(3, 3) += 1 / (c.sigma_ba * c.sigma_ba);
    const Eigen::Matrix4d P = L.inverse();
    const Eigen::Vector4d a_v(1, sign * g * T, -sign * g * T * T / 2, -T);
    const Eigen::Vector4d a_th(0, 1, -T, 0);  // dtheta(T) = dtheta_0 - T db_g
    var_v = a_v.dot(P * a_v);
    var_th = a_th.dot(P * a_th);
    var_bg = P(2, 2);
    var_ba = P(3, 3);
  };
  double vx, thy, bgy, bax, vy, thx, bgx, bay;
  horizontal(0, +1, vx, thy, bgy, bax);
  horizontal(1, -1, vy, thx, bgx, bay);
  // Vertical: information [[S0, -S1], [-S1, S2 + 1/sigma_ba^2]] on (dv_z0, db_az).
  double S0 = 0, S1 = 0, S2 = 0;
  for (const Point& p : c.pts)
    if (std::abs(p.d_l.z()) > 0.5) {
      const double t = p.t - 100.0;
      S0 += w;
      S1 += w * t;
      S2 += w * t * t;
    }
  const double c22 = S2 + 1 / (c.sigma_ba * c.sigma_ba), det = S0 * c22 - S1 * S1;
  const double var_v0 = c22 / det, var_baz = S0 / det, cov_vba = S1 / det;
  const double vz = var_v0 + T * T * var_baz - 2 * T * cov_vba;

  const double rel = 1e-9;
  EXPECT_NEAR(b.velocity, std::sqrt(vx + vy + vz), rel * b.velocity);
  EXPECT_NEAR(b.gravity_deg, std::sqrt(thx + thy) * 180 / M_PI, rel * b.gravity_deg);
  EXPECT_NEAR(b.gyro_bias, std::sqrt(bgx + bgy + c.sigma_bg * c.sigma_bg), rel * b.gyro_bias);
  EXPECT_NEAR(b.accel_bias, std::sqrt(bax + bay + var_baz), rel * b.accel_bias);
  // The horizontal accelerometer bias cannot be told from tilt at rest: it stays at its prior,
  // and the tilt is limited by it (atan(sigma_ba / g) per axis).
  EXPECT_NEAR(std::sqrt(bax), c.sigma_ba, 1e-3 * c.sigma_ba);
  EXPECT_GT(std::sqrt(thy), 0.999 * c.sigma_ba / g);
}

TEST(CramerRaoBound, UnobservableQuantitiesAreInfinite) {
  // At rest without bias priors: the tilt and the horizontal accelerometer bias are one unknown
  // (g dtheta - db_a), the yaw-rate bias is not seen; the velocity stays observable.
  const Bound rest = StaticCase(kNoPrior, kNoPrior).bound();
  ASSERT_TRUE(rest.ok);
  EXPECT_TRUE(std::isfinite(rest.velocity) && rest.velocity > 0);
  EXPECT_TRUE(std::isinf(rest.gravity_deg));
  EXPECT_TRUE(std::isinf(rest.gyro_bias));
  EXPECT_TRUE(std::isinf(rest.accel_bias));
  // No measurement at all: nothing but the priors, no velocity.
  BoundModel m = rigModel();
  m.gyro_bias_prior_sigma = 0.01;
  m.accel_bias_prior_sigma = 0.1;
  const auto traj = movingTrajectory();
  const Bound none = CramerRaoBound(m, nodesOf(traj, 0, 10, 200.0)).compute();
  ASSERT_TRUE(none.ok);
  EXPECT_EQ(none.measurements, 0u);
  EXPECT_TRUE(std::isinf(none.velocity));
  EXPECT_TRUE(std::isinf(none.gravity_deg));
  EXPECT_NEAR(none.gyro_bias, std::sqrt(3.0) * 0.01, 1e-9);
  EXPECT_NEAR(none.accel_bias, std::sqrt(3.0) * 0.1, 1e-9);
}

TEST(ZeroRateBound, MatchesTheClosedForm) {
  // No prior, equal axes: sigma sqrt(3 / N).
  EXPECT_NEAR(zeroRateGyroBiasBound(Vec3::Constant(0.002), 100), 0.002 * std::sqrt(3.0 / 100),
              1e-15);
  EXPECT_NEAR(zeroRateGyroBiasBound(Vec3::Constant(0.004), 12), 0.004 * std::sqrt(3.0 / 12), 1e-15);
  // Per axis with a prior, against the least squares of N samples y_k = b_g + n_k written out:
  // information H^T W H + I / sigma_0^2, H the stacked identities.
  const Vec3 sigma(0.001, 0.002, 0.004);
  const double sigma0 = 0.003;
  const int n = 40;
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(3 * n, 3);
  Eigen::VectorXd w(3 * n);
  for (int k = 0; k < n; ++k) {
    H.block<3, 3>(3 * k, 0).setIdentity();
    w.segment<3>(3 * k) = sigma.cwiseAbs2().cwiseInverse();
  }
  const Eigen::Matrix3d info =
      H.transpose() * w.asDiagonal() * H + Eigen::Matrix3d::Identity() / (sigma0 * sigma0);
  const double expected = std::sqrt(info.inverse().trace());
  EXPECT_NEAR(zeroRateGyroBiasBound(sigma, n, sigma0), expected, 1e-12 * expected);
  // Without rest nothing; an exact gyro at rest knows its bias.
  EXPECT_TRUE(std::isnan(zeroRateGyroBiasBound(sigma, 0, sigma0)));
  EXPECT_EQ(zeroRateGyroBiasBound(Vec3::Zero(), 10, sigma0), 0.0);
}

TEST(ZeroRateBound, CountsTheWindowsNodesAtRest) {
  // At rest throughout: every node, the closed form with the model's per-axis noise and prior,
  // and below the bound that does not know of the rest (the yaw-rate bias keeps its prior there).
  BoundModel m;
  m.gyro_axis_scale = Vec3(0.9, 1.0, 1.1);
  m.gyro_bias_prior_sigma = 0.015;
  const StaticCase rest(0.015, 0.1);
  CramerRaoBound at_rest(m, rest.nodes);
  for (const Point& p : rest.pts) at_rest.addDoppler(p.t, p.d_l);
  const Bound b = at_rest.compute();
  ASSERT_TRUE(b.ok);
  EXPECT_EQ(b.rest_nodes, rest.nodes.size());
  EXPECT_DOUBLE_EQ(b.gyro_bias_zero_rate,
                   zeroRateGyroBiasBound(m.gyroSigmaPerAxis(), rest.nodes.size(), 0.015));
  EXPECT_LT(b.gyro_bias_zero_rate, 0.2 * b.gyro_bias);
  // Moving throughout: none.
  const auto traj = movingTrajectory();
  const Bound moving = CramerRaoBound(m, nodesOf(traj, 0.2, 20, 200.0)).compute();
  EXPECT_EQ(moving.rest_nodes, 0u);
  EXPECT_TRUE(std::isnan(moving.gyro_bias_zero_rate));
  // Starting: the nodes before the motion only.
  std::vector<KinematicTruth> starting(rest.nodes.begin(), rest.nodes.begin() + 30);
  for (const KinematicTruth& s : nodesOf(traj, 0.2, 20, 200.0)) {
    KinematicTruth later = s;
    later.t = starting.back().t + 0.005;
    starting.push_back(later);
  }
  const Bound start = CramerRaoBound(m, starting).compute();
  EXPECT_EQ(start.rest_nodes, 30u);
  EXPECT_DOUBLE_EQ(start.gyro_bias_zero_rate,
                   zeroRateGyroBiasBound(m.gyroSigmaPerAxis(), 30, 0.015));
}

TEST(CramerRaoBound, RejectsBadInput) {
  const auto traj = movingTrajectory();
  const auto nodes = nodesOf(traj, 0, 4, 200.0);
  BoundModel m;
  m.doppler_sigma = 0;
  EXPECT_THROW(CramerRaoBound(m, nodes), std::invalid_argument);
  m = BoundModel{};
  m.gyro_bias_prior_sigma = 0;
  EXPECT_THROW(CramerRaoBound(m, nodes), std::invalid_argument);
  EXPECT_THROW(CramerRaoBound(BoundModel{}, {nodes[0]}), std::invalid_argument);
  EXPECT_THROW(CramerRaoBound(BoundModel{}, {nodes[1], nodes[0]}), std::invalid_argument);
  CramerRaoBound b(BoundModel{}, nodes);
  EXPECT_FALSE(b.addDoppler(nodes.back().t + 1e-3, Vec3::UnitX()));  // outside the window
  EXPECT_TRUE(b.addDoppler(nodes.back().t, Vec3::UnitX()));          // the state time is in
  EXPECT_THROW(b.addDoppler(nodes[1].t, Vec3::Zero()), std::invalid_argument);
}

TEST(SimulatorBound, UsesEveryStaticPointOfTheWindowAndNothingElse) {
  auto sc = sim::preset("stat_02", 3);  // a street with moving cars and pedestrians
  sc.duration = 0.6;
  sc.points_per_frame = 4000;
  sc.outlier_ratio = 0.05;
  const sim::Recording rec = sim::simulate(sc);
  const double t0 = rec.imu[10].t, t1 = rec.imu[90].t;
  std::size_t n_static = 0, n_other = 0;
  for (std::size_t f = 0; f < rec.frames.size(); ++f)
    for (std::size_t i = 0; i < rec.frames[f].points.size(); ++i) {
      const double t =
          rec.frames[f].stamp + static_cast<double>(rec.frames[f].points[i].time_offset);
      if (t < t0 || t > t1) continue;
      (rec.labels[f][i] == sim::PointLabel::Static ? n_static : n_other)++;
    }
  ASSERT_GT(n_other, 100u);  // outliers and moving objects are there, and left out
  FreeInitConfig cfg;
  const Bound b = sim::cramerRaoBound(rec, sim::boundModel(rec, cfg), t0, t1);
  ASSERT_TRUE(b.ok) << b.message;
  EXPECT_EQ(b.measurements, n_static);
  EXPECT_EQ(b.nodes, 81u);
  EXPECT_DOUBLE_EQ(b.t_end, t1);
  // The estimator's priors bound the biases from above; at rest the yaw-rate bias keeps its prior.
  EXPECT_LE(b.gyro_bias, std::sqrt(3.0) * cfg.imu.gyro_bias_sigma0);
  EXPECT_GE(b.gyro_bias, cfg.imu.gyro_bias_sigma0);
  EXPECT_LE(b.accel_bias, std::sqrt(3.0) * cfg.imu.accel_bias_prior_sigma);
  // A result without a state has no window and no bound.
  InitResult none;
  EXPECT_FALSE(sim::cramerRaoBound(rec, cfg, none).ok);
}

// The bound is the physical limit of the simulated unit: its true per-axis IMU noise and Doppler
// noise, whatever noise the estimator was handed in its configuration.
TEST(SimulatorBound, UsesTheTrueNoiseNeverTheDeclared) {
  auto sc = sim::preset("dyna_01", 2);
  sc.duration = 0.4;
  sc.points_per_frame = 2000;
  sc.gyro_sigma = 0.003;
  sc.gyro_sigma_scale = Vec3(0.8, 1.0, 1.2);
  sc.accel_sigma = 0.03;
  sc.accel_sigma_scale = Vec3(1.1, 0.9, 1.15);
  sc.doppler_sigma = 0.04;
  const sim::Recording rec = sim::simulate(sc);
  FreeInitConfig declared;  // the defaults: 0.002 rad/s, 0.02 m/s^2, 0.03 m/s
  FreeInitConfig told_more = declared;
  told_more.imu.gyro_sigma = 0.012;
  told_more.imu.accel_sigma = 0.12;
  told_more.doppler.doppler_sigma = 0.12;
  for (const FreeInitConfig* cfg : {&declared, &told_more}) {
    const BoundModel m = sim::boundModel(rec, *cfg);
    EXPECT_LT((m.gyroSigmaPerAxis() - Vec3(0.0024, 0.003, 0.0036)).norm(), 1e-15);
    EXPECT_EQ(m.accelSigmaPerAxis(), sc.accelSigmaPerAxis());
    EXPECT_EQ(m.doppler_sigma, 0.04);
  }
  const double t0 = rec.imu[5].t, t1 = rec.imu[60].t;
  const Bound a = sim::cramerRaoBound(rec, sim::boundModel(rec, declared), t0, t1);
  const Bound b = sim::cramerRaoBound(rec, sim::boundModel(rec, told_more), t0, t1);
  ASSERT_TRUE(a.ok && b.ok);
  EXPECT_EQ(a.cov, b.cov);
  // One figure per sensor: the RMS over the axes.
  const sim::NoiseFigures truth = sim::trueNoise(rec);
  EXPECT_NEAR(truth.gyro, 0.003 * std::sqrt((0.64 + 1.0 + 1.44) / 3), 1e-15);
  EXPECT_NEAR(truth.accel, 0.03 * std::sqrt((1.21 + 0.81 + 1.3225) / 3), 1e-15);
  EXPECT_EQ(truth.doppler, 0.04);
}

}  // namespace
}  // namespace freeinit::eval
