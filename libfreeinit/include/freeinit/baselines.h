// Initializers LiDAR-inertial systems use today, with the same output type as Free-Init, so they
// can be compared on equal terms. All assume what their originals assume (a platform at rest).
#pragma once

#include <freeinit/initial_state.h>
#include <freeinit/types.h>

#include <string>
#include <vector>

namespace freeinit::baselines {

/// FAST-LIO2's static-mean initialization over the first `imu_samples` samples: b_g = mean gyro,
/// gravity = -mean accel scaled to 9.81, zero velocity, zero accelerometer bias.
/// The attitude is reported gravity-aligned (world z up) so it compares with Free-Init's.
InitResult fastLio2(const std::vector<ImuSample>& imu, int imu_samples = 100);

/// DLIO's initialization: means over `duration` seconds (3 s in DLIO), gravity-aligned attitude,
/// b_g = mean gyro, b_a along the mean accel only (magnitude error), zero velocity.
InitResult dlio(const std::vector<ImuSample>& imu, double duration = 3.0);

/// Per-frame Doppler-only least squares: the LiDAR velocity of the last frame in the window from
/// its static points (IRLS), turned into a body velocity with the mean gyro of the frame. Attitude
/// and biases as FAST-LIO2 (it measures velocity only).
InitResult dopplerLeastSquares(const std::vector<ImuSample>& imu,
                               const std::vector<LidarFrame>& frames, const Extrinsics& extrinsics,
                               int imu_samples = 100);

/// The body velocity one frame's Doppler returns give on their own (the per-frame least squares
/// above): what that method reports for the frame, e.g. to plot it over time.
struct FrameVelocity {
  InitStatus status = InitStatus::NotEnoughData;
  std::string message;              ///< why not, when !ok()
  double t_mid = 0;                 ///< [s] UNIX, middle of the frame's point times
  Vec3 v_b = Vec3::Zero();          ///< [m/s] body velocity in b
  Mat3 cov_v_b = Mat3::Identity();  ///< [(m/s)^2]
  bool ok() const { return status == InitStatus::Ok; }
};

/// The per-frame Doppler least squares of one frame; `imu` gives the mean gyro over the frame for
/// the lever arm.
FrameVelocity dopplerFrameVelocity(const LidarFrame& frame, const std::vector<ImuSample>& imu,
                                   const Extrinsics& extrinsics);

}  // namespace freeinit::baselines
