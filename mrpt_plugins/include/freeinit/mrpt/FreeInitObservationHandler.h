// Feeds MRPT observations, one at a time and in any interleaving a rawlog or a live grabber
// produces, to the Free-Init estimator. Used by the offline app and by the live path.
#pragma once

#include <freeinit/free_init.h>
#include <freeinit/mrpt/app_config.h>
#include <mrpt/obs/CObservation.h>
#include <mrpt/poses/CPose3D.h>

#include <memory>
#include <optional>
#include <vector>

namespace freeinit::mrpt_glue {

class FreeInitObservationHandler {
 public:
  explicit FreeInitObservationHandler(const AppConfig& config);

  /// Processes one observation. Returns true if it was used (an IMU or point cloud with the
  /// configured label), false if ignored (other sensors, or the state is already ready()).
  /// Throws std::invalid_argument on an unusable observation (no Doppler, time going back...).
  bool process(const mrpt::obs::CObservation::Ptr& obs);

  /// End of input: closes a window still open with what is there.
  void finish();

  bool ready() const;
  /// The result; status NotEnoughData until ready().
  const InitResult& result() const;
  /// The extrinsics in use (from the INI or, once a cloud arrived, from the sensorPose).
  const Extrinsics& extrinsics() const { return config_.core.extrinsics; }

  std::size_t imuCount() const { return imu_count_; }
  std::size_t frameCount() const { return frame_count_; }

 private:
  void start();  // builds the estimator once the extrinsics are known

  AppConfig config_;
  std::unique_ptr<FreeInit> estimator_;
  std::optional<mrpt::poses::CPose3D> imu_pose_;
  std::vector<ImuSample> pending_imu_;  ///< IMU before the first cloud when from_sensor_pose
  InitResult empty_;
  std::size_t imu_count_ = 0, frame_count_ = 0;
};

}  // namespace freeinit::mrpt_glue
