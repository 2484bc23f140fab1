// SO(3) helpers shared by the whole core.
//
// Rotation convention: R_ab rotates vectors expressed in frame b into frame a (v_a = R_ab v_b).
// Exp/Log are the SO(3) exponential and logarithm of a rotation vector phi [rad]
// (R = Exp(phi) rotates by |phi| about phi/|phi|, right-handed). Perturbations used in the
// project are right (body-frame) perturbations: R_true = R_est * Exp(dtheta).
// The templated versions work with ceres::Jet for autodiff.
#pragma once

#include <freeinit/types.h>

#include <cmath>

namespace freeinit {

/// Skew-symmetric matrix [v]x such that [v]x u = v x u.
template <typename T>
Eigen::Matrix<T, 3, 3> skew(const Eigen::Matrix<T, 3, 1>& v) {
  Eigen::Matrix<T, 3, 3> m;
  m << T(0), -v(2), v(1),  //
      v(2), T(0), -v(0),   //
      -v(1), v(0), T(0);
  return m;
}
/// Skew-symmetric matrix of a double vector (accepts Eigen expressions).
inline Mat3 skew(const Vec3& v) { return skew<double>(v); }

/// SO(3) exponential of the rotation vector phi [rad] (Rodrigues' formula, Taylor series for
/// small angles so that it stays exact and differentiable at phi = 0).
template <typename T>
Eigen::Matrix<T, 3, 3> Exp(const Eigen::Matrix<T, 3, 1>& phi) {
  using std::cos;
  using std::sin;
  using std::sqrt;
  const T theta2 = phi.squaredNorm();
  const Eigen::Matrix<T, 3, 3> K = skew<T>(phi);
  T a;  // sin(theta)/theta
  T b;  // (1 - cos(theta))/theta^2
  if (theta2 < T(1e-10)) {
    a = T(1) - theta2 / T(6);
    b = T(0.5) - theta2 / T(24);
  } else {
    const T theta = sqrt(theta2);
    a = sin(theta) / theta;
    b = (T(1) - cos(theta)) / theta2;
  }
  return Eigen::Matrix<T, 3, 3>::Identity() + a * K + b * (K * K);
}
/// SO(3) exponential of a double rotation vector [rad] (accepts Eigen expressions).
inline Mat3 Exp(const Vec3& phi) { return Exp<double>(phi); }

/// SO(3) logarithm: the rotation vector [rad] with |phi| in [0, pi]. R must be a rotation matrix.
inline Vec3 Log(const Mat3& R) {
  const Eigen::AngleAxisd aa(R);  // robust near 0 and pi (Eigen uses the quaternion)
  Vec3 phi = aa.angle() * aa.axis();
  if (!phi.allFinite()) phi.setZero();
  return phi;
}

/// Angle between two non-zero vectors [rad], in [0, pi] (numerically stable at 0 and pi).
inline double angleBetween(const Vec3& a, const Vec3& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

/// Gravity-aligned attitude with zero yaw from gravity measured in the body frame.
/// Returns R_wb = Ry(pitch) Rx(roll) (ZYX Euler angles with yaw = 0) such that
/// R_wb * g_b / |g_b| = (0, 0, -1), i.e. the world z axis points up.
/// For an accelerometer at rest pass g_b = -accel (specific force points up).
/// Precondition: |g_b| > 0. At pitch = +-90 deg the roll is set to 0.
inline Mat3 alignToGravity(const Vec3& g_b) {
  const Vec3 up_b = -g_b.normalized();  // world z axis seen from the body
  const double pitch = std::atan2(-up_b.x(), std::hypot(up_b.y(), up_b.z()));
  const double roll = std::atan2(up_b.y(), up_b.z());
  return (Eigen::AngleAxisd(pitch, Vec3::UnitY()) * Eigen::AngleAxisd(roll, Vec3::UnitX()))
      .toRotationMatrix();
}

/// Yaw of R_wb in ZYX Euler angles [rad] (rotation about the world z axis).
inline double yawOf(const Mat3& R_wb) { return std::atan2(R_wb(1, 0), R_wb(0, 0)); }

}  // namespace freeinit
