#include <freeinit/mrpt/FreeInitObservationHandler.h>
#include <freeinit/mrpt/conversions.h>
#include <freeinit/mrpt/input_validator.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace freeinit::mrpt_glue {

FreeInitObservationHandler::FreeInitObservationHandler(const AppConfig& config) : config_(config) {
  config_.core.validate();
  extrinsics_known_ = !config_.extrinsics.from_sensor_pose;
  imu_check_samples_ = std::max<std::size_t>(2, kLiveImuCheckSamples);
}

void FreeInitObservationHandler::checkImu() {
  const auto& in = config_.input;
  if (auto problem = imuRateProblem(held_imu_, in.min_imu_rate))
    throw std::invalid_argument(*problem);
  if (auto problem = accelUnitProblem(held_imu_, in.imu_accel_in_g))
    throw std::invalid_argument(*problem);
  imu_checked_ = true;
}

void FreeInitObservationHandler::feed() {
  if (!imu_checked_ || !extrinsics_known_) return;
  if (!estimator_) estimator_ = std::make_unique<FreeInit>(config_.core);
  std::size_t next_imu = 0;
  for (auto& [imu_before, frame] : held_frames_) {
    for (; next_imu < imu_before; ++next_imu) estimator_->addImu(held_imu_[next_imu]);
    estimator_->addFrame(std::move(frame));
  }
  for (; next_imu < held_imu_.size(); ++next_imu) estimator_->addImu(held_imu_[next_imu]);
  held_imu_.clear();
  held_frames_.clear();
}

bool FreeInitObservationHandler::process(const mrpt::obs::CObservation::Ptr& obs) {
  if (!obs || ready()) return false;
  const auto& in = config_.input;
  if (auto imu = std::dynamic_pointer_cast<mrpt::obs::CObservationIMU>(obs)) {
    if (!in.imu_label.empty() && imu->sensorLabel != in.imu_label) return false;
    const ImuSample s = imuFromObservation(*imu, in.imu_accel_in_g ? kGravity : 1.0);
    if (!imu_pose_) imu_pose_ = imu->sensorPose;
    if (imu_count_ > 0 && s.t <= last_imu_t_)
      throw std::invalid_argument("IMU timestamps must increase");
    last_imu_t_ = s.t;
    ++imu_count_;
    if (estimator_) {
      estimator_->addImu(s);
      return true;
    }
    held_imu_.push_back(s);
    if (!imu_checked_ && held_imu_.size() >= imu_check_samples_) checkImu();
    feed();
    return true;
  }
  if (auto pc = std::dynamic_pointer_cast<mrpt::obs::CObservationPointCloud>(obs)) {
    if (!in.lidar_label.empty() && pc->sensorLabel != in.lidar_label) return false;
    LidarFrame f = frameFromObservation(*pc);
    auto invalid = [](const DopplerPoint& p) {
      return !p.p_l.allFinite() || !std::isfinite(p.doppler) || !std::isfinite(p.time_offset);
    };
    if (in.drop_invalid_points) {
      f.points.erase(std::remove_if(f.points.begin(), f.points.end(), invalid), f.points.end());
    } else if (std::any_of(f.points.begin(), f.points.end(), invalid)) {
      throw std::invalid_argument("point cloud with NaN or infinite points");
    }
    if (!f.points.empty())
      if (auto problem = dopplerProblem(f.points)) throw std::invalid_argument(*problem);
    if (!extrinsics_known_) {
      const mrpt::poses::CPose3D imu_p = imu_pose_ ? *imu_pose_ : mrpt::poses::CPose3D();
      config_.core.extrinsics = extrinsicsFromPose(pc->sensorPose - imu_p);
      extrinsics_known_ = true;
    }
    ++frame_count_;
    if (estimator_) {
      estimator_->addFrame(std::move(f));
      return true;
    }
    held_frames_.emplace_back(held_imu_.size(), std::move(f));
    feed();
    return true;
  }
  return false;
}

void FreeInitObservationHandler::finish() {
  if (!imu_checked_) checkImu();
  extrinsics_known_ = true;  // no cloud came: the configured extrinsics, as before
  feed();
  estimator_->finish();
}

bool FreeInitObservationHandler::ready() const { return estimator_ && estimator_->ready(); }

const InitResult& FreeInitObservationHandler::result() const {
  return estimator_ ? estimator_->result() : empty_;
}

}  // namespace freeinit::mrpt_glue
