// The two input streams of an initialization, buffered and handed out in time order.
//
// IMU samples and LiDAR frames arrive in any interleaving, each stream in time order. The
// sequencer checks each record once as it arrives (finite, increasing, frames not reaching back
// into the previous one), keeps the frames where the caller or the sequencer holds them, and lets
// an estimator walk the points in time order with a cursor, knowing which parts of the time axis
// both streams have covered. Shared by the initialization pipelines and the odometry.
#pragma once

#include <freeinit/types.h>

#include <deque>
#include <limits>
#include <memory>
#include <vector>

namespace freeinit::detail {

class MeasurementSequencer {
 public:
  /// A buffered frame: its points stay where the caller or owned_ keeps them.
  struct FrameRef {
    double stamp = 0;
    const std::vector<DopplerPoint>* points = nullptr;
  };
  /// Position of a point: frame index and point index.
  struct Cursor {
    std::size_t f = 0, p = 0;
  };

  /// Throws std::invalid_argument if the sample is not finite or its time does not increase.
  void checkImu(const ImuSample& s) const;
  /// checkImu, then buffers the sample.
  void addImu(const ImuSample& s);
  /// Throws std::invalid_argument unless the frame can follow the buffered ones (see checkFrame).
  void addFrame(LidarFrame&& f);
  /// As addFrame, without copying: the caller keeps `f` alive as long as the sequencer.
  void addBorrowedFrame(const LidarFrame& f);
  /// As addFrame, sharing the frame (it must not change while shared).
  void addSharedFrame(std::shared_ptr<const LidarFrame> f);
  /// Throws std::invalid_argument unless `f` can follow the buffered frames
  /// (input::frameOrderProblem).
  void checkFrame(const LidarFrame& f) const;

  void finish() { finished_ = true; }
  bool finished() const { return finished_; }

  const std::vector<ImuSample>& imu() const { return imu_; }
  const std::vector<FrameRef>& frames() const { return frames_; }

  /// Moves `c` to the next existing point; false when the buffered frames are exhausted.
  bool normalize(Cursor& c) const {
    while (c.f < frames_.size() && c.p >= frames_[c.f].points->size()) {
      ++c.f;
      c.p = 0;
    }
    return c.f < frames_.size();
  }
  /// UNIX time of the point at a normalized cursor.
  double time(const Cursor& c) const {
    return frames_[c.f].stamp + static_cast<double>((*frames_[c.f].points)[c.p].time_offset);
  }
  const DopplerPoint& point(const Cursor& c) const { return (*frames_[c.f].points)[c.p]; }

  /// UNIX time of the last buffered point, or -inf.
  double lidarCoveredUntil() const;
  /// Every LiDAR point before UNIX time t has been received: a point at or after t exists, or
  /// the input has ended (frames arrive in time order).
  bool lidarPassed(double t) const { return finished_ || lidarCoveredUntil() >= t; }

 private:
  std::vector<ImuSample> imu_;
  std::deque<LidarFrame> owned_;  ///< frames handed to addFrame (stable addresses)
  std::vector<std::shared_ptr<const LidarFrame>> shared_;  ///< frames shared with the caller
  std::vector<FrameRef> frames_;                           ///< all frames in time order
  bool finished_ = false;
};

}  // namespace freeinit::detail
