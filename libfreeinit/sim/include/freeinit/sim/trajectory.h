// The exact body (IMU) state of a simulated recording and the interface of trajectories that give
// it.
#pragma once

#include <freeinit/types.h>

namespace freeinit::sim {

/// Exact kinematic state of the body (IMU) frame at time t.
struct TruthState {
  double t = 0;                  ///< [s] UNIX time
  Mat3 R_wb = Mat3::Identity();  ///< body attitude in the (gravity-aligned, z up) world
  Vec3 p_w = Vec3::Zero();       ///< [m] body origin in w
  Vec3 v_w = Vec3::Zero();       ///< [m/s] body velocity in w
  Vec3 a_w = Vec3::Zero();       ///< [m/s^2] body acceleration in w
  Vec3 omega_b = Vec3::Zero();   ///< [rad/s] body angular velocity in b
  Vec3 alpha_b = Vec3::Zero();   ///< [rad/s^2] body angular acceleration in b
};

/// A C2-smooth trajectory whose derivatives are available analytically at any time.
class Trajectory {
 public:
  virtual ~Trajectory() = default;
  virtual TruthState at(double t) const = 0;
};

}  // namespace freeinit::sim
