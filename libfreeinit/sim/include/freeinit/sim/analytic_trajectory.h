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
// With ramp_poly the polynomial part p of h enters through its rate instead,
//   c(tau) = c_start + int_{tau_s}^{tau} S p' + S (w(tau) - w(tau_s)),   w the sinusoids,
// so that a start from rest ramps the cruise speed up as S p' (no overshoot); the integral of the
// polynomial S p' is evaluated in closed form.
//
// The six channels describe a rig frame r (the platform carrying LiDAR and IMU) in a path frame
// whose x axis is the direction of travel. Two constant rotations complete the body state:
// the IMU is mounted on the rig at R_rb (R_wb = R_wr R_rb, omega_b = R_rb^T omega_r), and the
// path frame is turned by `heading` about the world z axis (p_w = Rz(heading) p_path). Both are
// the identity by default, and then skipped, so that such a trajectory is the plain z-y-x one.
#pragma once

#include <freeinit/sim/trajectory.h>

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
  double t0 = 0;                    ///< [s] UNIX time of tau = 0
  Vec3 p_start_w = Vec3::Zero();    ///< [m] position at tau = tau_s
  Vec3 rpy_start = Vec3::Zero();    ///< [rad] roll, pitch, yaw at tau = tau_s
  std::array<ScalarSignal, 3> pos;  ///< x, y, z motion signals [m]
  std::array<ScalarSignal, 3> rpy;  ///< roll, pitch, yaw motion signals [rad]
  double still_until = 0;           ///< [s] tau_s: motion (re)starts here, relative to t0
  double blend_duration = 0;        ///< [s] smoothstep length; <= 0 means no standstill at all
  bool ramp_poly = false;           ///< the polynomial parts enter through their rates (above)
  Mat3 R_rb = Mat3::Identity();     ///< IMU (body) mounting on the rig
  double heading = 0;               ///< [rad] yaw of the path frame in the world
};

/// The analytic trajectory of every simulated scenario.
class AnalyticTrajectory : public Trajectory {
 public:
  explicit AnalyticTrajectory(TrajectoryParams params);
  TruthState at(double t) const override;
  const TrajectoryParams& params() const { return params_; }

 private:
  /// (c, c', c'') of channel i (x y z roll pitch yaw) at tau, including the standstill gate.
  Eigen::Vector3d channel(std::size_t i, double tau) const;

  TrajectoryParams params_;
  /// (c, c', c'') of channel i with ramp_poly, at x = (tau - tau_s) / T_blend > 0.
  Eigen::Vector3d rampedChannel(std::size_t i, double tau, double x) const;

  std::array<Eigen::Vector3d, 6> h_at_start_;  ///< h(tau_s) per channel (x y z r p y)
  /// ramp_poly: per channel, p'(tau_s + T x) and int_0^x S p'(tau_s + T xi) dxi as polynomials in
  /// x, the latter's value at x = 1, p(tau_s + T) and w(tau_s).
  struct Ramp {
    std::vector<double> rate, integral;
    double integral_at_end = 0, poly_at_end = 0, waves_at_start = 0;
  };
  std::array<Ramp, 6> ramp_;
  bool mounted_ = false;               ///< R_rb is not the identity
  Mat3 R_heading_ = Mat3::Identity();  ///< Rz(heading), used when heading != 0
};

}  // namespace freeinit::sim
