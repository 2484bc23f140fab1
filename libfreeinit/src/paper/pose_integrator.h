// Pose integration at every velocimeter update (paper Eq. (pose_integ_continuous)).
// Between two updates the angular velocity is taken as linear in time: the rotation increment is
// the midpoint rotation vector plus the coning correction (omega_0 x omega_1) dt^2 / 12, exact to
// third order in dt; the position uses the trapezoidal rule on v_w = R_wb v_b.
#pragma once

#include <freeinit/types.h>

namespace freeinit {

class PoseIntegrator {
 public:
  /// Starts at the identity pose at time t.
  void reset(double t, const Vec3& omega_b, const Vec3& v_b);
  /// Integrates up to time t, where the body rates are omega_b and v_b.
  void integrate(double t, const Vec3& omega_b, const Vec3& v_b);

  double time() const { return t_; }
  const Quat& q_wb() const { return q_wb_; }
  Mat3 R_wb() const { return q_wb_.toRotationMatrix(); }
  const Vec3& p_w() const { return p_w_; }
  const Vec3& v_w() const { return v_w_; }

 private:
  double t_ = 0;
  Quat q_wb_ = Quat::Identity();
  Vec3 p_w_ = Vec3::Zero();
  Vec3 v_w_ = Vec3::Zero();
  Vec3 omega_b_ = Vec3::Zero();
  int steps_since_normalize_ = 0;
};

}  // namespace freeinit
