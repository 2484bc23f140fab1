// Free-Init: the initializer facade. Feed IMU samples and LiDAR frames in any interleaving (each
// stream in time order); it runs the velocimeter, integrates the pose, maps static points and, when
// the window closes, solves for the accelerometer bias and gravity.
#pragma once

#include <freeinit/config.h>
#include <freeinit/initial_state.h>

#include <memory>

namespace freeinit {

class FreeInit {
 public:
  explicit FreeInit(const FreeInitConfig& config);
  ~FreeInit();
  FreeInit(FreeInit&&) noexcept;
  FreeInit& operator=(FreeInit&&) noexcept;

  /// Adds one IMU sample. Throws std::invalid_argument if it is not finite or its time does not
  /// increase (programmer or input error: validate recordings first). Ignored once ready().
  void addImu(const ImuSample& s);
  /// Adds one LiDAR frame. Throws std::invalid_argument if its stamp does not increase, a time
  /// offset is not finite, its points are not sorted by time or it overlaps the previous frame in
  /// time. Ignored once ready().
  void addFrame(const LidarFrame& f);
  /// As above, taking the frame's points without copying them.
  void addFrame(LidarFrame&& f);
  /// As above, sharing the frame without copying it (several estimators, or a recorder, may
  /// hold the same frame); it must not change while shared.
  void addFrame(std::shared_ptr<const LidarFrame> f);
  /// Declares the end of the input: a window still open is closed with what is there.
  void finish();

  /// True once the window is closed and result() is final.
  bool ready() const;
  /// The result (status NotEnoughData until ready()). The first call after ready() builds the
  /// static map (the joint estimator maps its returns after the state is out; not thread-safe,
  /// as nothing here is).
  const InitResult& result() const;
  /// The result as soon as ready(), before its map: everything but static_map and rejected
  /// (empty until result() is called) is final. What an online user waits for: on a window of
  /// 300,000 returns the map is about a third of the call that closes the window.
  const InitResult& resultBeforeMap() const;

  /// Batch convenience: runs over whole recordings (throws as addImu/addFrame on bad input).
  /// The trajectory's attitudes include the gravity solve's gyro-bias correction; positions and
  /// map points come from the last pass, integrated with the bias the previous solve corrected.
  static InitResult run(const FreeInitConfig& config, const std::vector<ImuSample>& imu,
                        const std::vector<LidarFrame>& frames);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace freeinit
