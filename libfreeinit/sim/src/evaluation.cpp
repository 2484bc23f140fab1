#include <freeinit/rotation.h>
#include <freeinit/sim/evaluation.h>

#include <Eigen/Eigenvalues>

#include <cmath>

namespace freeinit::sim {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

/// e^T C^+ e with the pseudo-inverse on the numerically non-zero eigen-directions.
template <int N>
double nees(const Eigen::Matrix<double, N, 1>& e, const Eigen::Matrix<double, N, N>& C) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, N, N>> es(C);
  const double max_ev = es.eigenvalues().maxCoeff();
  double s = 0;
  for (int i = 0; i < N; ++i) {
    const double ev = es.eigenvalues()(i);
    if (ev <= max_ev * 1e-9) continue;
    const double proj = es.eigenvectors().col(i).dot(e);
    s += proj * proj / ev;
  }
  return s;
}

}  // namespace

InitErrors evaluate(const InitialState& state, const Recording& rec) {
  InitErrors err;
  if (!state.ok()) return err;
  err.valid = true;
  const TruthState truth = rec.truth(state.timestamp);
  const Mat3 R_wb = state.q_wb.toRotationMatrix();
  const Vec3 v_b = state.v_b();
  const Vec3 g_b = state.g_b();
  const Vec3 v_b_true = truth.R_wb.transpose() * truth.v_w;
  const Vec3 g_b_true = truth.R_wb.transpose() * rec.g_w;
  err.vel_b = (v_b - v_b_true).norm();
  err.vel_b_true_norm = v_b_true.norm();
  err.gravity_deg = angleBetween(g_b, g_b_true) * kRadToDeg;
  err.gyro_bias = (state.b_g - rec.b_g).norm();
  err.accel_bias_vector = state.b_a - rec.b_a;
  err.accel_bias = err.accel_bias_vector.norm();
  const Vec3 up_b = -g_b_true.normalized();
  err.accel_bias_vertical = std::abs((state.b_a - rec.b_a).dot(up_b));
  err.gravity_deg_from_bias = gravityErrorFromBiasDeg(rec.b_a, g_b_true);

  // Linear maps from the 18-dim error state to each gauge-free error (right perturbation):
  //   dv_b = R^T dv_w + [v_b]x dtheta;   dg_b = [g_b]x dtheta (tangent);   db = db.
  const Cov18& P = state.cov;
  Eigen::Matrix<double, 3, 18> A = Eigen::Matrix<double, 3, 18>::Zero();
  A.block<3, 3>(0, kVel) = R_wb.transpose();
  A.block<3, 3>(0, kTheta) = skew(v_b);
  const Vec3 e_v = v_b - v_b_true;
  err.nees_vel_b = nees<3>(e_v, A * P * A.transpose());
  // Tilt: g_b,true = g_b + [g_b]x dtheta gives g^ x g^_true = -dtheta projected on the plane
  // orthogonal to gravity; its covariance is the projected attitude block (rank 2).
  const Vec3 g_hat = g_b.normalized();
  const Vec3 e_tilt = g_hat.cross(g_b_true.normalized());
  const Mat3 Pt = Mat3::Identity() - g_hat * g_hat.transpose();
  err.nees_tilt = nees<3>(e_tilt, Mat3(Pt * P.block<3, 3>(kTheta, kTheta) * Pt));
  err.nees_gyro_bias = nees<3>(Vec3(state.b_g - rec.b_g), Mat3(P.block<3, 3>(kBg, kBg)));
  err.nees_accel_bias = nees<3>(Vec3(state.b_a - rec.b_a), Mat3(P.block<3, 3>(kBa, kBa)));
  return err;
}

double gravityErrorFromBiasDeg(const Vec3& b_a_true, const Vec3& g_b_true) {
  const Vec3 up_b = -g_b_true.normalized();
  const Vec3 ba_h = b_a_true - b_a_true.dot(up_b) * up_b;
  return std::atan2(ba_h.norm(), kGravity) * kRadToDeg;
}

}  // namespace freeinit::sim
