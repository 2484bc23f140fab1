// The evaluation module's scoring of a state: gauge-free errors, their Jacobian against finite
// differences, the NEES of a consistent covariance, the truth file and its interpolation, and the
// error / bound ratio.
#include <freeinit/eval/bound_ratio.h>
#include <freeinit/eval/state_errors.h>
#include <freeinit/eval/truth_file.h>
#include <freeinit/rotation.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>

#include "test_stats.h"

namespace freeinit::eval {
namespace {

using Vec18 = Eigen::Matrix<double, 18, 1>;

/// A moving, tilted estimate with a full covariance, in a world yawed against the truth's.
InitialState sampleState() {
  InitialState s;
  s.status = InitStatus::Ok;
  s.timestamp = 10;
  s.q_wb = Quat(Exp(Vec3(0.1, -0.2, 0.7)));
  s.p_w = Vec3(1, 2, 3);
  s.v_w = Vec3(1.5, -0.4, 0.2);
  s.b_g = Vec3(0.01, -0.005, 0.002);
  s.b_a = Vec3(0.05, 0.1, -0.02);
  s.g_w = Vec3(0, 0, -kGravity);
  Eigen::Matrix<double, 18, 18> L = Eigen::Matrix<double, 18, 18>::Zero();
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n01;
  const double sig[6] = {0.01, 0.05, 0.02, 0.003, 0.04, 0.001};  // per block
  for (int i = 0; i < 18; ++i)
    for (int j = 0; j <= i; ++j) L(i, j) = (i == j ? 1.0 : 0.3 * n01(rng)) * sig[i / 3];
  s.cov = L * L.transpose();
  return s;
}

/// The truth `s` would be if its error were dz: R_true = R Exp(dtheta), the rest additive; seen
/// in a world yawed by `yaw` against the state's.
StateTruth truthOf(const InitialState& s, const Vec18& dz, double yaw) {
  const Quat q_yaw(Eigen::AngleAxisd(yaw, Vec3::UnitZ()));
  StateTruth t;
  t.t = s.timestamp;
  t.q_wb = q_yaw * Quat(Mat3(s.q_wb.toRotationMatrix() * Exp(Vec3(dz.segment<3>(kTheta)))));
  t.p_w = q_yaw * (s.p_w + dz.segment<3>(kPos));
  t.v_w = q_yaw * (s.v_w + dz.segment<3>(kVel));
  t.b_g = s.b_g + dz.segment<3>(kBg);
  t.b_a = s.b_a + dz.segment<3>(kBa);
  t.g_w = q_yaw * (s.g_w + dz.segment<3>(kGrav));
  return t;
}

/// The gauge-free errors truth - estimate as gaugeFreeJacobian orders them.
Eigen::Matrix<double, 11, 1> gaugeFreeErrors(const InitialState& s, const StateTruth& t) {
  Eigen::Matrix<double, 11, 1> e;
  e.segment<3>(0) = t.v_b() - s.v_b();
  e.segment<2>(3) =
      tiltBasis(s.g_b()).transpose() * t.g_b().normalized().cross(s.g_b().normalized());
  e.segment<3>(5) = t.b_g - s.b_g;
  e.segment<3>(8) = t.b_a - s.b_a;
  return e;
}

TEST(StateErrors, GaugeFreeJacobianMatchesFiniteDifferences) {
  const InitialState s = sampleState();
  const double eps = 1e-6;
  Eigen::Matrix<double, 11, 18> fd;
  for (int j = 0; j < 18; ++j) {
    Vec18 dz = Vec18::Zero();
    dz(j) = eps;
    fd.col(j) =
        (gaugeFreeErrors(s, truthOf(s, dz, 0.4)) - gaugeFreeErrors(s, truthOf(s, -dz, 0.4))) /
        (2 * eps);
  }
  const Eigen::Matrix<double, 11, 18> A = gaugeFreeJacobian(s);
  EXPECT_LT((A - fd).cwiseAbs().maxCoeff(), 1e-8 * A.cwiseAbs().maxCoeff()) << A << "\n\n" << fd;
}

TEST(StateErrors, AreFreeOfTheWorldFrame) {
  const InitialState s = sampleState();
  Vec18 dz = Vec18::Zero();
  dz.segment<3>(kVel) = s.q_wb * Vec3(0.3, 0, -0.4);  // 0.5 m/s in b
  dz.segment<3>(kBg) = Vec3(0, 0.002, 0);
  dz.segment<3>(kBa) = Vec3(0, 0, 0.05);
  Vec18 tilt = Vec18::Zero();
  tilt.segment<3>(kTheta) = Vec3(0.01, 0, 0);  // about the body x axis
  const Vec3 g_hat = s.g_b().normalized();
  const double tilt_rad = (Vec3(0.01, 0, 0) - 0.01 * g_hat.x() * g_hat).norm();
  for (const double yaw : {0.0, 1.3, -2.9}) {
    SCOPED_TRACE(yaw);
    const StateErrors e = stateErrors(s, truthOf(s, dz, yaw));
    EXPECT_NEAR(e.velocity, 0.5, 1e-12);
    EXPECT_NEAR(e.speed, s.v_w.norm(), 0.5 + 1e-12);
    EXPECT_NEAR(e.gravity_deg, 0, 1e-9);
    EXPECT_NEAR(e.gyro_bias, 0.002, 1e-12);
    EXPECT_NEAR(e.accel_bias, 0.05, 1e-12);
    // The part of the attitude error orthogonal to gravity tilts it.
    EXPECT_NEAR(stateErrors(s, truthOf(s, tilt, yaw)).gravity_deg, tilt_rad * 180 / M_PI, 1e-6);
  }
}

TEST(StateNees, IsChiSquareForErrorsDrawnFromTheCovariance) {
  // Truths drawn around the estimate with its own covariance: each block's mean NEES over many
  // draws is its number of degrees of freedom (two-sided 99.9 % interval of the chi-square mean).
  const InitialState s = sampleState();
  const Eigen::LLT<Eigen::Matrix<double, 18, 18>> llt(s.cov);
  const Eigen::Matrix<double, 18, 18> L = llt.matrixL();
  std::mt19937_64 rng(5);
  std::normal_distribution<double> n01;
  const int n = 4000;
  double sum[4] = {0, 0, 0, 0};
  for (int i = 0; i < n; ++i) {
    Vec18 u;
    for (int k = 0; k < 18; ++k) u(k) = n01(rng);
    const Nees e = stateNees(s, truthOf(s, L * u, 0.8));
    sum[0] += e.velocity;
    sum[1] += e.tilt;
    sum[2] += e.gyro_bias;
    sum[3] += e.accel_bias;
  }
  const double dof[4] = {3, 2, 3, 3};
  for (int b = 0; b < 4; ++b) {
    SCOPED_TRACE(b);
    EXPECT_GT(sum[b], test::chi2Quantile(n * dof[b], -3.29));
    EXPECT_LT(sum[b], test::chi2Quantile(n * dof[b], 3.29));
  }
}

TEST(TruthFile, RoundTripsAndInterpolates) {
  const std::string path =
      (std::filesystem::temp_directory_path() / "freeinit_test_truth.csv").string();
  std::vector<StateTruth> truth(2);
  truth[0].t = 1700000000.25;
  truth[0].v_w = Vec3(1, 0, 0);
  truth[0].b_g = Vec3(0.01, -0.02, 0.003);
  truth[1] = truth[0];
  truth[1].t = truth[0].t + 0.5;
  truth[1].q_wb = Quat(Eigen::AngleAxisd(0.2, Vec3::UnitZ()));
  truth[1].p_w = Vec3(0.5, 0, 0);
  truth[1].v_w = Vec3(3, 0, 0);
  writeTruthCsv(path, truth);
  const auto back = readTruthCsv(path);
  ASSERT_EQ(back.size(), 2u);
  EXPECT_NEAR(back[1].t - back[0].t, 0.5, 1e-6);
  EXPECT_LT((back[0].b_g - truth[0].b_g).norm(), 1e-12);
  const auto mid = interpolateTruth(back, truth[0].t + 0.125);
  ASSERT_TRUE(mid);
  EXPECT_NEAR(mid->v_w.x(), 1.5, 1e-5);
  EXPECT_NEAR(Eigen::AngleAxisd(mid->q_wb).angle(), 0.05, 1e-6);
  EXPECT_FALSE(interpolateTruth(back, truth[0].t - 0.01));
  EXPECT_FALSE(interpolateTruth(back, truth[1].t + 0.01));
  // Bad input names the file and the line.
  std::ofstream(path, std::ios::app)
      << "1700000000.5,0,0,0,1,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,-9.81\n";
  try {
    readTruthCsv(path);
    ADD_FAILURE() << "accepted a time that goes back";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path + ": line 4: time does not increase"),
              std::string::npos)
        << e.what();
  }
  std::ofstream(path) << "t,p_x\n1,2,3\n";
  EXPECT_THROW(readTruthCsv(path), std::runtime_error);
  std::filesystem::remove(path);
}

TEST(BoundRatio, HandlesMissingAndInfiniteBounds) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_DOUBLE_EQ(boundRatio(0.3, 0.1), 3.0);
  EXPECT_TRUE(std::isnan(boundRatio(nan, 0.1)));
  EXPECT_TRUE(std::isnan(boundRatio(0.3, nan)));
  EXPECT_EQ(boundRatio(0.3, inf), 0.0);  // nothing can be known: no error is too large
  EXPECT_TRUE(std::isinf(boundRatio(0.3, 0.0)));
  // Confident wrong: more than 3x the bound and above what a user notices.
  EXPECT_TRUE(confidentlyWrong(0.031, 0.01, 0.02));
  EXPECT_FALSE(confidentlyWrong(0.029, 0.01, 0.02));   // within 3x
  EXPECT_FALSE(confidentlyWrong(0.019, 0.001, 0.02));  // not noticed
  EXPECT_FALSE(confidentlyWrong(0.5, inf, 0.02));
  EXPECT_FALSE(confidentlyWrong(nan, 0.01, 0.02));
}

}  // namespace
}  // namespace freeinit::eval
