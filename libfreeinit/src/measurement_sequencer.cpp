#include "measurement_sequencer.h"

#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <string>

namespace freeinit::detail {
namespace {

/// A UNIX time with enough digits to tell two samples apart.
std::string stamp(double t) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(6) << t;
  return os.str();
}

}  // namespace

void MeasurementSequencer::checkImu(const ImuSample& s) const {
  if (!s.gyro.allFinite() || !s.accel.allFinite() || !std::isfinite(s.t))
    throw std::invalid_argument("IMU sample at t=" + stamp(s.t) + " is not finite");
  if (!imu_.empty() && s.t <= imu_.back().t)
    throw std::invalid_argument("IMU time does not increase: " + stamp(s.t) + " after " +
                                stamp(imu_.back().t));
}

void MeasurementSequencer::addImu(const ImuSample& s) {
  checkImu(s);
  imu_.push_back(s);
}

void MeasurementSequencer::checkFrame(const LidarFrame& f) const {
  if (!std::isfinite(f.stamp)) throw std::invalid_argument("LiDAR frame stamp is not finite");
  if (!frames_.empty() && f.stamp <= frames_.back().stamp)
    throw std::invalid_argument("LiDAR frame stamp does not increase: " + stamp(f.stamp) +
                                " after " + stamp(frames_.back().stamp));
  for (std::size_t i = 0; i < f.points.size(); ++i) {
    if (!std::isfinite(f.points[i].time_offset))
      throw std::invalid_argument("LiDAR frame at " + stamp(f.stamp) + ": point " +
                                  std::to_string(i) + " has a non-finite time offset");
    if (i > 0 && f.points[i].time_offset < f.points[i - 1].time_offset)
      throw std::invalid_argument("LiDAR frame at " + stamp(f.stamp) +
                                  ": points are not sorted by time (point " + std::to_string(i) +
                                  ")");
  }
  // Points are processed in time order across frames: a frame may not reach back into the
  // previous one.
  if (f.points.empty()) return;
  const double last = lidarCoveredUntil();
  if (f.stamp + static_cast<double>(f.points.front().time_offset) < last)
    throw std::invalid_argument("LiDAR frame at " + stamp(f.stamp) +
                                " overlaps the previous frame in time");
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

double MeasurementSequencer::lidarCoveredUntil() const {
  for (std::size_t f = frames_.size(); f-- > 0;)
    if (!frames_[f].points->empty())
      return frames_[f].stamp + static_cast<double>(frames_[f].points->back().time_offset);
  return -std::numeric_limits<double>::infinity();
}

}  // namespace freeinit::detail
