#include <freeinit/eval/state_errors.h>
#include <freeinit/rotation.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>

namespace freeinit::eval {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

/// e^T C^+ e with the pseudo-inverse on the numerically non-zero eigen-directions of C.
template <int N>
double nees(const Eigen::Matrix<double, N, 1>& e, const Eigen::Matrix<double, N, N>& C) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, N, N>> es(C);
  const double max_ev = es.eigenvalues().maxCoeff();
  double s = 0;
  for (int i = 0; i < N; ++i) {
    const double ev = es.eigenvalues()(i);
    if (!(ev > max_ev * 1e-9)) continue;
    const double proj = es.eigenvectors().col(i).dot(e);
    s += proj * proj / ev;
  }
  return s;
}

}  // namespace

Eigen::Matrix<double, 3, 2> tiltBasis(const Vec3& g) {
  const Vec3 n = g.normalized();
  // The axis least aligned with g gives a well-conditioned first direction.
  Eigen::Index axis = 0;
  n.cwiseAbs().minCoeff(&axis);
  const Vec3 e1 = n.cross(Vec3::Unit(axis)).normalized();
  Eigen::Matrix<double, 3, 2> B;
  B.col(0) = e1;
  B.col(1) = n.cross(e1);
  return B;
}

StateErrors stateErrors(const InitialState& s, const StateTruth& truth) {
  StateErrors e;
  e.t = s.timestamp;
  e.v_b_true = truth.v_b();
  e.speed = e.v_b_true.norm();
  e.velocity_vector = s.v_b() - e.v_b_true;
  e.velocity = e.velocity_vector.norm();
  const Vec3 g_b_true = truth.g_b();
  e.gravity_deg = angleBetween(s.g_b(), g_b_true) * kRadToDeg;
  e.gyro_bias_vector = s.b_g - truth.b_g;
  e.gyro_bias = e.gyro_bias_vector.norm();
  e.accel_bias_vector = s.b_a - truth.b_a;
  e.accel_bias = e.accel_bias_vector.norm();
  e.accel_bias_vertical = std::abs(e.accel_bias_vector.dot(g_b_true.normalized()));
  e.gravity_deg_from_bias = gravityErrorFromBiasDeg(truth.b_a, g_b_true);
  return e;
}

double gravityErrorFromBiasDeg(const Vec3& b_a_true, const Vec3& g_b_true) {
  const Vec3 up_b = -g_b_true.normalized();
  const Vec3 ba_h = b_a_true - b_a_true.dot(up_b) * up_b;
  return std::atan2(ba_h.norm(), kGravity) * kRadToDeg;
}

double displacementError(const InitResult& r, const StateTruth& at_start,
                         const StateTruth& at_end) {
  if (!r.state.ok() || r.trajectory.empty()) return std::numeric_limits<double>::quiet_NaN();
  const PoseSample& p0 = r.trajectory.front();
  const Vec3 d_est = p0.q_wb.conjugate() * (r.state.p_w - p0.p_w);
  const Vec3 d_true = at_start.q_wb.conjugate() * (at_end.p_w - at_start.p_w);
  return (d_est - d_true).norm();
}

// Derivation (right perturbation R_true = R Exp(dtheta), v_w,true = v_w + dv, g_w,true = g_w + dg):
//   v_b,true = Exp(-dtheta) R^T (v_w + dv) = v_b + [v_b]x dtheta + R^T dv;
//   g_b,true = g_b + [g_b]x dtheta + R^T dg, so with unit vectors g^ = g_b / |g|,
//   g^_true x g^ = (g^ + g^ x dtheta + P R^T dg / |g|) x g^ = P dtheta - [g^]x R^T dg / |g|,
//   P = I - g^ g^T the projection on the plane orthogonal to gravity (B^T P = B^T).
Eigen::Matrix<double, 11, 18> gaugeFreeJacobian(const InitialState& s) {
  const Mat3 R = s.q_wb.toRotationMatrix();
  const Vec3 g_b = s.g_b();
  const Vec3 g_hat = g_b.normalized();
  const Eigen::Matrix<double, 3, 2> B = tiltBasis(g_b);
  Eigen::Matrix<double, 11, 18> A = Eigen::Matrix<double, 11, 18>::Zero();
  A.block<3, 3>(0, kTheta) = skew(s.v_b());
  A.block<3, 3>(0, kVel) = R.transpose();
  A.block<2, 3>(3, kTheta) = B.transpose();
  A.block<2, 3>(3, kGrav) = -B.transpose() * skew(g_hat) * R.transpose() / g_b.norm();
  A.block<3, 3>(5, kBg) = Mat3::Identity();
  A.block<3, 3>(8, kBa) = Mat3::Identity();
  return A;
}

Nees stateNees(const InitialState& s, const StateTruth& truth) {
  const Eigen::Matrix<double, 11, 18> A = gaugeFreeJacobian(s);
  const Eigen::Matrix<double, 11, 11> C = A * s.cov * A.transpose();
  const Vec3 g_hat = s.g_b().normalized();
  const Vec3 g_hat_true = truth.g_b().normalized();
  const Eigen::Vector2d e_tilt = tiltBasis(s.g_b()).transpose() * g_hat_true.cross(g_hat);
  Nees n;
  n.velocity = nees<3>(Vec3(truth.v_b() - s.v_b()), Mat3(C.block<3, 3>(0, 0)));
  n.tilt = nees<2>(e_tilt, Eigen::Matrix2d(C.block<2, 2>(3, 3)));
  n.gyro_bias = nees<3>(Vec3(truth.b_g - s.b_g), Mat3(C.block<3, 3>(5, 5)));
  n.accel_bias = nees<3>(Vec3(truth.b_a - s.b_a), Mat3(C.block<3, 3>(8, 8)));
  return n;
}

OwnSigmas ownSigmas(const InitialState& s) {
  const Eigen::Matrix<double, 11, 18> A = gaugeFreeJacobian(s);
  const Eigen::Matrix<double, 11, 11> C = A * s.cov * A.transpose();
  // A block without variance is one the estimator gave no covariance for (a baseline's).
  auto root = [&](int begin, int size) {
    const double t = C.block(begin, begin, size, size).trace();
    return t > 0 ? std::sqrt(t) : std::numeric_limits<double>::quiet_NaN();
  };
  OwnSigmas o;
  o.velocity = root(0, 3);
  o.gravity_deg = root(3, 2) * kRadToDeg;
  o.gyro_bias = root(5, 3);
  o.accel_bias = root(8, 3);
  return o;
}

}  // namespace freeinit::eval
