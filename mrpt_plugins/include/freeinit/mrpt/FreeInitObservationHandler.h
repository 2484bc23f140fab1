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
  /// The input checks of the offline validator apply here too (input_validator.h): every cloud's
  /// Doppler; the IMU rate and accelerometer unit on the first kLiveImuCheckSamples IMU samples,
  /// which are held back (with the clouds between them) until they pass, so the estimator never
  /// sees data that fails them. Few samples, so that the estimator keeps up with a live stream
  /// from early on (holding back a whole window made the closing call process all of it).
  bool process(const mrpt::obs::CObservation::Ptr& obs);

  /// End of input: checks the IMU if not yet done, then closes a window still open with what is
  /// there.
  void finish();

  bool ready() const;
  /// The result; status NotEnoughData until ready().
  const InitResult& result() const;
  /// The extrinsics in use (from the INI or, once a cloud arrived, from the sensorPose).
  const Extrinsics& extrinsics() const { return config_.core.extrinsics; }

  std::size_t imuCount() const { return imu_count_; }
  std::size_t frameCount() const { return frame_count_; }

 private:
  void checkImu();  // throws std::invalid_argument if the held-back IMU fails the input checks
  void feed();      // hands the held-back data to the estimator once checked and extrinsics known

  AppConfig config_;
  std::unique_ptr<FreeInit> estimator_;
  std::optional<mrpt::poses::CPose3D> imu_pose_;
  bool extrinsics_known_ = false;
  bool imu_checked_ = false;
  std::size_t imu_check_samples_ = 0;
  /// IMU samples and clouds in arrival order, held until the checks passed and (when
  /// from_sensor_pose) the first cloud gave the extrinsics.
  std::vector<ImuSample> held_imu_;
  std::vector<std::pair<std::size_t, LidarFrame>> held_frames_;  ///< (IMU samples before it, cloud)
  double last_imu_t_ = 0;
  InitResult empty_;
  std::size_t imu_count_ = 0, frame_count_ = 0;
};

}  // namespace freeinit::mrpt_glue
