#include <freeinit/mrpt/FreeInitObservationHandler.h>
#include <freeinit/mrpt/conversions.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace freeinit::mrpt_glue {

FreeInitObservationHandler::FreeInitObservationHandler(const AppConfig& config) : config_(config) {
  config_.core.validate();
  if (!config_.extrinsics.from_sensor_pose) start();
}

void FreeInitObservationHandler::start() {
  estimator_ = std::make_unique<FreeInit>(config_.core);
  for (const auto& s : pending_imu_) estimator_->addImu(s);
  pending_imu_.clear();
}

bool FreeInitObservationHandler::process(const mrpt::obs::CObservation::Ptr& obs) {
  if (!obs || ready()) return false;
  const auto& in = config_.input;
  if (auto imu = std::dynamic_pointer_cast<mrpt::obs::CObservationIMU>(obs)) {
    if (!in.imu_label.empty() && imu->sensorLabel != in.imu_label) return false;
    const ImuSample s = imuFromObservation(*imu, in.imu_accel_in_g ? kGravity : 1.0);
    if (!imu_pose_) imu_pose_ = imu->sensorPose;
    if (estimator_) {
      estimator_->addImu(s);
    } else {
      if (!pending_imu_.empty() && s.t <= pending_imu_.back().t)
        throw std::invalid_argument("IMU timestamps must increase");
      pending_imu_.push_back(s);
    }
    ++imu_count_;
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
    if (!estimator_) {
      const mrpt::poses::CPose3D imu_p = imu_pose_ ? *imu_pose_ : mrpt::poses::CPose3D();
      config_.core.extrinsics = extrinsicsFromPose(pc->sensorPose - imu_p);
      start();
    }
    estimator_->addFrame(std::move(f));
    ++frame_count_;
    return true;
  }
  return false;
}

void FreeInitObservationHandler::finish() {
  if (!estimator_) start();
  estimator_->finish();
}

bool FreeInitObservationHandler::ready() const { return estimator_ && estimator_->ready(); }

const InitResult& FreeInitObservationHandler::result() const {
  return estimator_ ? estimator_->result() : empty_;
}

}  // namespace freeinit::mrpt_glue
