// Doppler-inertial odometry after the initialization: the velocimeter and the pose integration
// keep running from the initial state over the rest of a recording, giving the body pose in the
// initialization's world frame at every IMU sample. No map and no scan matching: the position
// drifts with the integrated velocity error, but the velocity is measured (Doppler) at every point,
// so forward motion stays observable where scan matching sees none (a featureless tunnel).
#pragma once

#include <freeinit/config.h>
#include <freeinit/initial_state.h>

#include <vector>

namespace freeinit {

/// The body state at one IMU sample, world frame of the InitialState.
struct OdometrySample {
  double t = 0;  ///< [s] UNIX time
  Quat q_wb = Quat::Identity();
  Vec3 p_w = Vec3::Zero();      ///< [m]
  Vec3 v_b = Vec3::Zero();      ///< [m/s] body velocity in b
  Vec3 omega_b = Vec3::Zero();  ///< [rad/s] bias-free angular velocity in b
};

class DopplerInertialOdometry {
 public:
  /// `state` must be ok(). The velocimeter restarts at state.timestamp from the state's velocity,
  /// gyro bias and their covariances (no second bootstrap); with `accel_aided` its propagation uses
  /// the accelerometer with the state's b_a and gravity (as the refinement passes do).
  /// Throws std::invalid_argument if the state is not ok.
  DopplerInertialOdometry(const FreeInitConfig& config, const InitialState& state,
                          bool accel_aided = true);

  /// Runs over whole recordings (each in time order, as FreeInit::run takes them); data up to
  /// state.timestamp are skipped. Returns one sample per IMU sample from the state time on, the
  /// first one being the initial state itself. Throws std::invalid_argument if no IMU sample
  /// follows the state time.
  std::vector<OdometrySample> run(const std::vector<ImuSample>& imu,
                                  const std::vector<LidarFrame>& frames) const;

 private:
  FreeInitConfig config_;
  InitialState state_;
  bool accel_aided_;
};

}  // namespace freeinit
