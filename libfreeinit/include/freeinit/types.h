// Free-Init core types. Conventions (see docs/architecture.md, "Frames, signs and the output
// contract"):
//   w world, b body (= IMU), l LiDAR. R_ab rotates b-vectors into a; p_ab is the position of b's
//   origin in a. Doppler is the range rate: for a static point, doppler = -d_l^T v_l (negative when
//   approaching), d_l the unit direction from the LiDAR to the point in frame l.
//   Times are UNIX seconds (double).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

namespace freeinit {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Quat = Eigen::Quaterniond;

/// One IMU sample, body frame.
struct ImuSample {
  double t = 0;               ///< [s] UNIX time
  Vec3 gyro = Vec3::Zero();   ///< [rad/s] measured angular rate
  Vec3 accel = Vec3::Zero();  ///< [m/s^2] measured specific force
};

/// One Doppler LiDAR return, in the LiDAR frame at its own measurement time.
struct DopplerPoint {
  Eigen::Vector3f p_l = Eigen::Vector3f::Zero();  ///< [m] position w.r.t. the LiDAR at time t
  float doppler = 0;                              ///< [m/s] range rate (raw, not ego-compensated)
  float time_offset = 0;                          ///< [s] point time minus the frame stamp
  float intensity = 0;                            ///< [-] return intensity
  std::uint16_t line = 0;                         ///< scan line index
};

/// One LiDAR frame. Points are sorted by time_offset (non-decreasing).
struct LidarFrame {
  double stamp = 0;  ///< [s] UNIX time; point time = stamp + time_offset
  std::vector<DopplerPoint> points;
};

/// LiDAR-IMU extrinsics: the LiDAR pose in the body frame.
struct Extrinsics {
  Mat3 R_bl = Mat3::Identity();
  Vec3 p_bl = Vec3::Zero();  ///< [m]
};

/// Standard gravity magnitude used throughout [m/s^2].
inline constexpr double kGravity = 9.81;

}  // namespace freeinit
