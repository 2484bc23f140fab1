#include "measurement_sequencer.h"

#include <freeinit/input_checks.h>

#include <stdexcept>
#include <string>

namespace freeinit::detail {

void MeasurementSequencer::checkImu(const ImuSample& s) const {
  if (const auto problem = input::imuSampleProblem(s, imu_.empty() ? nullptr : &imu_.back()))
    throw std::invalid_argument("IMU sample at " + input::formatStamp(s.t) + ": " + *problem);
}

void MeasurementSequencer::addImu(const ImuSample& s) {
  checkImu(s);
  imu_.push_back(s);
}

void MeasurementSequencer::checkFrame(const LidarFrame& f) const {
  std::optional<double> previous_stamp, previous_end;
  if (!frames_.empty()) previous_stamp = frames_.back().stamp;
  const double end = lidarCoveredUntil();
  if (end > -std::numeric_limits<double>::infinity()) previous_end = end;
  if (const auto problem = input::frameOrderProblem(f, previous_stamp, previous_end))
    throw std::invalid_argument("LiDAR frame at " + input::formatStamp(f.stamp) + ": " + *problem);
}

void MeasurementSequencer::addFrame(LidarFrame&& f) {
  checkFrame(f);
  const LidarFrame& kept = owned_.emplace_back(std::move(f));
  frames_.push_back({kept.stamp, &kept.points});
}

void MeasurementSequencer::addBorrowedFrame(const LidarFrame& f) {
  checkFrame(f);
  frames_.push_back({f.stamp, &f.points});
}

void MeasurementSequencer::addSharedFrame(std::shared_ptr<const LidarFrame> f) {
  if (!f) throw std::invalid_argument("LiDAR frame: null");
  checkFrame(*f);
  frames_.push_back({f->stamp, &f->points});
  shared_.push_back(std::move(f));
}

double MeasurementSequencer::lidarCoveredUntil() const {
  for (std::size_t f = frames_.size(); f-- > 0;)
    if (!frames_[f].points->empty())
      return frames_[f].stamp + static_cast<double>(frames_[f].points->back().time_offset);
  return -std::numeric_limits<double>::infinity();
}

}  // namespace freeinit::detail
