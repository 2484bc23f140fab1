#include <freeinit/eval/imu_error_model.h>
#include <freeinit/rotation.h>

namespace freeinit::eval {

Mat18 errorDynamics(const KinematicTruth& s, const Vec3& g_w) {
  const Vec3 f_b = s.R_wb.transpose() * (s.a_w - g_w);
  Mat18 A = Mat18::Zero();
  A.block<3, 3>(kDTheta, kDTheta) = -skew(s.omega_b);
  A.block<3, 3>(kDTheta, kDBg) = -Mat3::Identity();
  A.block<3, 3>(kDTheta, kNg) = -Mat3::Identity();
  A.block<3, 3>(kDVel, kDTheta) = -s.R_wb * skew(f_b);
  A.block<3, 3>(kDVel, kDBa) = -s.R_wb;
  A.block<3, 3>(kDVel, kNa) = -s.R_wb;
  return A;
}

Mat12x18 errorTransition(const KinematicTruth& a, const KinematicTruth& b, const Vec3& g_w) {
  const double h = b.t - a.t;
  const Mat3& Ra = a.R_wb;
  const Mat3& Rb = b.R_wb;
  const Mat3 D = Ra.transpose() * Rb;
  // Hermite rule: int_0^h y = h/2 (y0 + y1) + h^2/12 (y0' - y1').
  // I = int D(s) ds with D' = D [omega]x.
  const Mat3 I =
      0.5 * h * (Mat3::Identity() + D) + h * h / 12.0 * (skew(a.omega_b) - D * skew(b.omega_b));
  // Y(s) = [V(s)]x R(s), V(s) = v(s) - v_a - g s: Y(0) = 0, Y' = [a_w - g]x R + [V]x R [omega]x.
  const Vec3 V = b.v_w - a.v_w - g_w * h;
  const Mat3 Yb = skew(V) * Rb;
  const Mat3 dYa = skew(Vec3(a.a_w - g_w)) * Ra;
  const Mat3 dYb = skew(Vec3(b.a_w - g_w)) * Rb + Yb * skew(b.omega_b);
  const Mat3 intY = 0.5 * h * Yb + h * h / 12.0 * (dYa - dYb);
  const Mat3 F = skew(V) * Ra * I - intY;

  Mat12x18 T = Mat12x18::Zero();
  T.block<3, 3>(kDTheta, kDTheta) = D.transpose();
  T.block<3, 3>(kDTheta, kDBg) = -D.transpose() * I;
  T.block<3, 3>(kDTheta, kNg) = -D.transpose() * I;
  T.block<3, 3>(kDVel, kDTheta) = -skew(V) * Ra;
  T.block<3, 3>(kDVel, kDVel) = Mat3::Identity();
  T.block<3, 3>(kDVel, kDBg) = F;
  T.block<3, 3>(kDVel, kNg) = F;
  T.block<3, 3>(kDVel, kDBa) = -Ra * I;
  T.block<3, 3>(kDVel, kNa) = -Ra * I;
  T.block<3, 3>(kDBg, kDBg) = Mat3::Identity();
  T.block<3, 3>(kDBa, kDBa) = Mat3::Identity();
  return T;
}

Mat3x18 lidarVelocityJacobian(const KinematicTruth& s, const Vec3& p_bl) {
  Mat3x18 C = Mat3x18::Zero();
  C.block<3, 3>(0, kDTheta) = skew(Vec3(s.R_wb.transpose() * s.v_w));
  C.block<3, 3>(0, kDVel) = s.R_wb.transpose();
  C.block<3, 3>(0, kDBg) = skew(p_bl);
  C.block<3, 3>(0, kNg) = skew(p_bl);
  return C;
}

Mat3x18 lidarVelocityJacobianRate(const KinematicTruth& s) {
  // The lever-arm columns are constant.
  const Vec3 v_b = s.R_wb.transpose() * s.v_w;
  const Vec3 dv_b = s.R_wb.transpose() * s.a_w - s.omega_b.cross(v_b);
  Mat3x18 dC = Mat3x18::Zero();
  dC.block<3, 3>(0, kDTheta) = skew(dv_b);
  dC.block<3, 3>(0, kDVel) = -skew(s.omega_b) * s.R_wb.transpose();
  return dC;
}

}  // namespace freeinit::eval
