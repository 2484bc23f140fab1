// The linearized IMU + Doppler error model of the Cramer-Rao bound: every hand-written Jacobian
// against central finite differences of the nonlinear model it linearizes, on a rotating,
// accelerating trajectory (several rad/s about every axis).
#include <freeinit/eval/cramer_rao_bound.h>
#include <freeinit/eval/imu_error_model.h>
#include <freeinit/rotation.h>
#include <freeinit/sim/analytic_trajectory.h>
#include <gtest/gtest.h>

#include <cmath>

#include "bound_trajectories.h"

namespace freeinit::eval {
namespace {

using Vec18 = Eigen::Matrix<double, 18, 1>;
using Vec12 = Eigen::Matrix<double, 12, 1>;

const Vec3 kG(0, 0, -kGravity);
using test::movingTrajectory;

KinematicTruth kinematics(const sim::Trajectory& traj, double t) {
  const sim::TruthState s = traj.at(t);
  return {t, s.R_wb, s.v_w, s.a_w, s.omega_b};
}

/// Biases of the nominal IMU (any value: the model is linearized about the truth).
const Vec3 kBg(0.01, -0.02, 0.015), kBa(0.1, -0.05, 0.08);

/// The nonlinear model from t_a to t_b with the perturbation z = [dtheta, dv, db_g, db_a, n_g, n_a]
/// of the state at t_a: the IMU samples the true motion (plus the nominal biases), the state is
/// integrated with the perturbed biases and noise by RK4 (quaternion and velocity, 400 steps),
/// and the result is returned as the error x(t_b) against the truth.
Vec12 propagateError(const sim::Trajectory& traj, double ta, double tb, const Vec18& z) {
  auto omega_m = [&](double t) { return Vec3(traj.at(t).omega_b + kBg); };
  auto f_m = [&](double t) {
    const auto s = traj.at(t);
    return Vec3(s.R_wb.transpose() * (s.a_w - kG) + kBa);
  };
  const Vec3 b_g = kBg + z.segment<3>(kDBg), b_a = kBa + z.segment<3>(kDBa);
  const Vec3 n_g = z.segment<3>(kNg), n_a = z.segment<3>(kNa);
  const auto sa = traj.at(ta);
  Eigen::Quaterniond q(Mat3(sa.R_wb * Exp(Vec3(z.segment<3>(kDTheta)))));
  Vec3 v = sa.v_w + z.segment<3>(kDVel);
  struct Deriv {
    Eigen::Vector4d dq;
    Vec3 dv;
  };
  auto deriv = [&](double t, const Eigen::Vector4d& qc, const Vec3& /*vc*/) {
    const Eigen::Quaterniond qq(qc(0), qc(1), qc(2), qc(3));
    const Vec3 w = omega_m(t) - b_g - n_g;
    const Eigen::Quaterniond qw(0, w.x(), w.y(), w.z());
    const Eigen::Quaterniond dq = qq * qw;
    Deriv d;
    d.dq = 0.5 * Eigen::Vector4d(dq.w(), dq.x(), dq.y(), dq.z());
    d.dv = qq.normalized() * Vec3(f_m(t) - b_a - n_a) + kG;
    return d;
  };
  const int steps = 400;
  const double h = (tb - ta) / steps;
  Eigen::Vector4d qv(q.w(), q.x(), q.y(), q.z());
  for (int i = 0; i < steps; ++i) {
    const double t = ta + i * h;
    const Deriv k1 = deriv(t, qv, v);
    const Deriv k2 = deriv(t + h / 2, qv + h / 2 * k1.dq, v + h / 2 * k1.dv);
    const Deriv k3 = deriv(t + h / 2, qv + h / 2 * k2.dq, v + h / 2 * k2.dv);
    const Deriv k4 = deriv(t + h, qv + h * k3.dq, v + h * k3.dv);
    qv += h / 6 * (k1.dq + 2 * k2.dq + 2 * k3.dq + k4.dq);
    v += h / 6 * (k1.dv + 2 * k2.dv + 2 * k3.dv + k4.dv);
  }
  const Mat3 R = Eigen::Quaterniond(qv(0), qv(1), qv(2), qv(3)).normalized().toRotationMatrix();
  const auto sb = traj.at(tb);
  Vec12 x;
  x.segment<3>(kDTheta) = Log(sb.R_wb.transpose() * R);
  x.segment<3>(kDVel) = v - sb.v_w;
  x.segment<3>(kDBg) = z.segment<3>(kDBg);
  x.segment<3>(kDBa) = z.segment<3>(kDBa);
  return x;
}

/// Central differences of f: R^18 -> R^n at 0.
template <typename F>
Eigen::MatrixXd centralDifferences(F&& f, int n, double eps) {
  Eigen::MatrixXd J(n, 18);
  for (int j = 0; j < 18; ++j) {
    Vec18 dz = Vec18::Zero();
    dz(j) = eps;
    J.col(j) = (f(dz) - f(-dz)) / (2 * eps);
  }
  return J;
}

/// max |A - B| over the entries, relative to max |B| (the scale of the Jacobian).
double relativeError(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B) {
  return (A - B).cwiseAbs().maxCoeff() / B.cwiseAbs().maxCoeff();
}

TEST(BoundModel, TransitionMatchesFiniteDifferencesOfTheNonlinearModel) {
  const auto traj = movingTrajectory();
  // An IMU interval at 200 Hz and a 4x longer one: the Hermite rule is exact to O(h^5).
  for (const double h : {0.005, 0.02}) {
    for (const double ta : {0.13, 0.71}) {
      SCOPED_TRACE(::testing::Message() << "h " << h << " t " << ta);
      const KinematicTruth a = kinematics(traj, ta), b = kinematics(traj, ta + h);
      ASSERT_GT(a.omega_b.norm(), 1.0);
      const Mat12x18 T = errorTransition(a, b, kG);
      const Eigen::MatrixXd fd = centralDifferences(
          [&](const Vec18& z) { return propagateError(traj, ta, ta + h, z); }, 12, 1e-5);
      EXPECT_LT(relativeError(T, fd), h < 0.01 ? 1e-8 : 2e-6) << "T\n" << T << "\nfd\n" << fd;
    }
  }
}

/// The Doppler model's inner vector v_b + omega x p_bl (body frame), perturbed by z at truth s.
Vec3 lidarVelocity(const sim::TruthState& s, const Vec3& p_bl, const Vec18& z) {
  const Mat3 R = s.R_wb * Exp(Vec3(z.segment<3>(kDTheta)));
  const Vec3 v_w = s.v_w + z.segment<3>(kDVel);
  const Vec3 gyro = s.omega_b + kBg;  // what the IMU measures
  const Vec3 omega = gyro - (kBg + z.segment<3>(kDBg)) - z.segment<3>(kNg);
  return R.transpose() * v_w + omega.cross(p_bl);
}

TEST(BoundModel, DopplerJacobianMatchesFiniteDifferences) {
  const auto traj = movingTrajectory();
  const Vec3 p_bl(0.08, -0.05, 0.12);
  for (const double t : {0.2, 0.9}) {
    const sim::TruthState s = traj.at(t);
    const Mat3x18 C = lidarVelocityJacobian(kinematics(traj, t), p_bl);
    const Eigen::MatrixXd fd =
        centralDifferences([&](const Vec18& z) { return lidarVelocity(s, p_bl, z); }, 3, 1e-6);
    EXPECT_LT(relativeError(C, fd), 1e-8) << "C\n" << C << "\nfd\n" << fd;
  }
}

/// The row map G(t) = C(t) T(t_a -> t) (z at t_a), T from errorTransition.
Mat3x18 rowMap(const sim::Trajectory& traj, double ta, double t, const Vec3& p_bl) {
  Mat18 T18 = Mat18::Identity();
  T18.topRows<12>() = errorTransition(kinematics(traj, ta), kinematics(traj, t), kG);
  return lidarVelocityJacobian(kinematics(traj, t), p_bl) * T18;
}

TEST(BoundModel, RowRateMatchesCentralDifferencesInTime) {
  // G'(t) = (C'(t) + C(t) A(t)) T(t): the rate and the dynamics against d/dt of C T.
  const auto traj = movingTrajectory();
  const Vec3 p_bl(0.08, -0.05, 0.12);
  const double ta = 0.4, tau = 1e-5;
  for (const double t : {0.4, 0.405}) {
    Mat18 T18 = Mat18::Identity();
    T18.topRows<12>() = errorTransition(kinematics(traj, ta), kinematics(traj, t), kG);
    const KinematicTruth s = kinematics(traj, t);
    const Mat3x18 dG =
        (lidarVelocityJacobianRate(s) + lidarVelocityJacobian(s, p_bl) * errorDynamics(s, kG)) *
        T18;
    const Mat3x18 fd =
        (rowMap(traj, ta, t + tau, p_bl) - rowMap(traj, ta, t - tau, p_bl)) / (2 * tau);
    EXPECT_LT(relativeError(dG, fd), 1e-6) << "dG\n" << dG << "\nfd\n" << fd;
  }
}

TEST(BoundModel, InterpolatedRowEqualsTheRowPropagatedToThePointTime) {
  // Within an interval a point's row is the cubic Hermite interpolation of G; against G computed
  // by propagating the interval's start to the point's own time.
  const auto traj = movingTrajectory();
  BoundModel model;
  model.extrinsics.R_bl = Exp(Vec3(0.3, -0.5, 1.0));
  model.extrinsics.p_bl = Vec3(0.08, -0.05, 0.12);
  std::vector<KinematicTruth> nodes;
  for (int k = 0; k <= 4; ++k) nodes.push_back(kinematics(traj, 0.3 + 0.005 * k));
  const CramerRaoBound bound(model, nodes);
  const Vec3 d_l = Vec3(0.9, -0.3, 0.2).normalized();
  for (std::size_t k = 0; k < bound.intervals(); ++k) {
    for (const double s : {0.0, 0.13, 0.5, 0.77, 1.0}) {
      const double t = nodes[k].t + s * (nodes[k + 1].t - nodes[k].t);
      const Eigen::Matrix<double, 1, 18> exact = -d_l.transpose() *
                                                 model.extrinsics.R_bl.transpose() *
                                                 rowMap(traj, nodes[k].t, t, model.extrinsics.p_bl);
      const Eigen::Matrix<double, 1, 18> row = bound.dopplerRow(k, t, d_l);
      EXPECT_LT(relativeError(row, exact), 2e-7) << "k " << k << " s " << s;
    }
  }
}

TEST(BoundModel, OutputJacobianMatchesFiniteDifferences) {
  // [v_b, tilt, b_g, b_a] at the last node as functions of the perturbed state.
  const auto traj = movingTrajectory();
  BoundModel model;
  std::vector<KinematicTruth> nodes = {kinematics(traj, 0.5), kinematics(traj, 0.505)};
  const CramerRaoBound bound(model, nodes);
  const sim::TruthState s = traj.at(0.505);
  const Eigen::Matrix<double, 3, 2> B = bound.outputJacobian().block<2, 3>(3, 0).transpose();
  const Vec3 g_hat = (s.R_wb.transpose() * kG).normalized();
  auto outputs = [&](const Vec18& z) {
    const Mat3 R = s.R_wb * Exp(Vec3(z.segment<3>(kDTheta)));
    const Vec3 v_w = s.v_w + z.segment<3>(kDVel);
    Eigen::Matrix<double, 11, 1> y;
    y.segment<3>(0) = R.transpose() * v_w;
    // The tilt: the rotation taking the true gravity direction to the perturbed one, in B.
    const Vec3 g_pert = (R.transpose() * kG).normalized();
    y.segment<2>(3) = B.transpose() * g_pert.cross(g_hat);
    y.segment<3>(5) = z.segment<3>(kDBg);
    y.segment<3>(8) = z.segment<3>(kDBa);
    return y;
  };
  const Eigen::MatrixXd fd = centralDifferences(outputs, 11, 1e-6);
  EXPECT_LT(relativeError(bound.outputJacobian(), fd.leftCols(12)), 1e-8)
      << bound.outputJacobian() << "\n\n"
      << fd;
}

TEST(BoundModel, WorldYawIsPropagatedExactlyAndUnseenByTheDoppler) {
  // Rotating the world about gravity changes no measurement: the transition maps the yaw direction
  // of one node onto that of the next, and no Doppler row sees it.
  const auto traj = movingTrajectory();
  BoundModel model;
  model.extrinsics.R_bl = Exp(Vec3(0.3, -0.5, 1.0));
  model.extrinsics.p_bl = Vec3(0.08, -0.05, 0.12);
  std::vector<KinematicTruth> nodes;
  for (int k = 0; k <= 3; ++k) nodes.push_back(kinematics(traj, 0.6 + 0.005 * k));
  const CramerRaoBound bound(model, nodes);
  for (std::size_t k = 0; k < bound.intervals(); ++k) {
    Vec18 z = Vec18::Zero();
    z.head<12>() = bound.yawDirection(k);
    const Vec12 next = bound.transition(k) * z;
    EXPECT_LT((next.normalized() - bound.yawDirection(k + 1)).norm(), 1e-12);
    for (const double s : {0.0, 0.4, 1.0}) {
      const double t = nodes[k].t + s * (nodes[k + 1].t - nodes[k].t);
      EXPECT_LT(std::abs(bound.dopplerRow(k, t, Vec3(0.3, 0.9, -0.2)) * z), 1e-12);
    }
  }
  EXPECT_LT((bound.outputJacobian() * bound.yawDirection(bound.intervals())).norm(), 1e-12);
}

}  // namespace
}  // namespace freeinit::eval
