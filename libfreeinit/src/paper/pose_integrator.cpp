#include "paper/pose_integrator.h"

#include <cmath>

namespace freeinit {
namespace {

/// Quaternion of the rotation vector phi; series expansion below 1e-4 rad (per-point steps).
Quat quatExp(const Vec3& phi) {
  const double theta2 = phi.squaredNorm();
  double c, s;  // cos(theta/2), sin(theta/2)/theta
  if (theta2 < 1e-8) {
    c = 1.0 - theta2 / 8.0;
    s = 0.5 - theta2 / 48.0;
  } else {
    const double theta = std::sqrt(theta2);
    c = std::cos(0.5 * theta);
    s = std::sin(0.5 * theta) / theta;
  }
  return Quat(c, s * phi.x(), s * phi.y(), s * phi.z());
}

}  // namespace

void PoseIntegrator::reset(double t, const Vec3& omega_b, const Vec3& v_b) {
  t_ = t;
  q_wb_.setIdentity();
  p_w_.setZero();
  v_w_ = v_b;
  omega_b_ = omega_b;
  steps_since_normalize_ = 0;
}

void PoseIntegrator::integrate(double t, const Vec3& omega_b, const Vec3& v_b) {
  const double dt = t - t_;
  if (dt <= 0) return;
  const Vec3 phi = 0.5 * (omega_b_ + omega_b) * dt + omega_b_.cross(omega_b) * (dt * dt / 12.0);
  q_wb_ = q_wb_ * quatExp(phi);
  if (++steps_since_normalize_ >= 64) {
    q_wb_.normalize();
    steps_since_normalize_ = 0;
  }
  const Vec3 v_w = q_wb_ * v_b;
  p_w_ += 0.5 * (v_w_ + v_w) * dt;
  v_w_ = v_w;
  omega_b_ = omega_b;
  t_ = t;
}

}  // namespace freeinit
