// A C-infinity (C2 where a standstill is blended in) analytic trajectory: every derivative the
// simulator needs is evaluated in closed form, never by finite differences.
//
// Attitude: R_wb = Rz(yaw) Ry(pitch) Rx(roll) (intrinsic z-y-x). With u = Rx^T e_y and
// w = Rx^T Ry^T e_z the body rate is omega_b = roll' e_x + pitch' u + yaw' w, and
// alpha_b = d/dt omega_b by the product rule (u', w' are analytic too).
// Each of the six channels (x, y, z, roll, pitch, yaw) is
//   c(tau) = c_start + S(tau) (h(tau) - h(tau_s)),   tau = t - t0,
// h a polynomial plus sinusoids, S a quintic smoothstep from 0 (tau <= tau_s) to 1
// (tau >= tau_s + T_blend), or S = 1 everywhere when T_blend <= 0.
#pragma once

#include <freeinit/sim/simulator.h>

#include <array>
#include <vector>

namespace freeinit::sim {

/// One sinusoid A sin(2 pi f tau + phase).
struct Sinusoid {
  double amplitude = 0;  ///< [m] or [rad]
  double freq_hz = 0;    ///< [Hz]
  double phase = 0;      ///< [rad]
};

/// A smooth scalar signal h(tau) = sum_k poly[k] tau^k + sum sinusoids.
struct ScalarSignal {
  std::vector<double> poly;     ///< coefficients of tau^k, units [m or rad]/s^k
  std::vector<Sinusoid> waves;  ///< superposed sinusoids

  /// (h, h', h'') at tau [s].
  Eigen::Vector3d eval(double tau) const;
};

/// Everything that defines an AnalyticTrajectory.
struct TrajectoryParams {
  double t0 = 0;                     ///< [s] UNIX time of tau = 0
  Vec3 p_start_w = Vec3::Zero();     ///< [m] position at tau = tau_s
  Vec3 rpy_start = Vec3::Zero();     ///< [rad] roll, pitch, yaw at tau = tau_s
  std::array<ScalarSignal, 3> pos;   ///< x, y, z motion signals [m]
  std::array<ScalarSignal, 3> rpy;   ///< roll, pitch, yaw motion signals [rad]
  double still_until = 0;            ///< [s] tau_s: motion (re)starts here, relative to t0
  double blend_duration = 0;         ///< [s] smoothstep length; <= 0 means no standstill at all
};

/// The analytic trajectory used by all presets.
class AnalyticTrajectory : public Trajectory {
 public:
  explicit AnalyticTrajectory(TrajectoryParams params);
  TruthState at(double t) const override;
  const TrajectoryParams& params() const { return params_; }

 private:
  /// (c, c', c'') of channel i (x y z roll pitch yaw) at tau, including the standstill gate.
  Eigen::Vector3d channel(std::size_t i, double tau) const;

  TrajectoryParams params_;
  std::array<Eigen::Vector3d, 6> h_at_start_;  ///< h(tau_s) per channel (x y z r p y)
};

}  // namespace freeinit::sim
