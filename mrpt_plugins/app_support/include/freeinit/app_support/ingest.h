// The one ingest path from the data to the estimator, in core types and free of MRPT: every
// source (a rawlog record, a live stream message; ingest_sources.h) becomes IngestItems, which a
// RecordChecker checks once per record (freeinit/input_checks.h) and InitSessions feed to the
// estimator. Several sessions may share one checker and the same frames (initializations at
// several starts of one recording, in one pass).
//
// What is an error and what a warning: a record that fails a check is not used, and it stops an
// initialization only if it lies inside that initialization's window (result.trajectory.front().t
// .. result.state.timestamp; the data fed so far when it did not initialize); outside, it is a
// warning. The stretch checks of a window (IMU rate, accelerometer unit) are errors. Every message
// names the source, the record and the reason.
#pragma once

#include <freeinit/app_support/app_config.h>
#include <freeinit/free_init.h>
#include <freeinit/input_checks.h>

#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace freeinit::app_support {

/// One observation of the input in core types.
struct IngestItem {
  enum class Kind { Imu, Frame, Other };
  Kind kind = Kind::Other;
  std::size_t record = 0;                   ///< rawlog record (live: observation number)
  double t = 0;                             ///< [UNIX s] the IMU sample time or the frame stamp
  std::optional<std::int64_t> stamp_ns;     ///< [ns] the exact stamp, when in the wire's range
  ImuSample imu;                            ///< Kind::Imu
  std::shared_ptr<const LidarFrame> frame;  ///< Kind::Frame, points sorted by time
  /// Kind::Frame: the LiDAR pose in the body frame it declares (a live stream's frames carry it;
  /// for a rawlog's clouds the RecordChecker sets it from the sensor poses).
  std::optional<Extrinsics> frame_extrinsics;
  /// The observation's sensorPose in the recording (a rawlog's IMU samples and clouds): the
  /// LiDAR's pose in the body frame is the cloud's relative to the IMU's.
  std::optional<Extrinsics> sensor_pose;
  std::string what;     ///< Kind::Other: "<class> '<label>'", counted and reported as ignored
  std::string problem;  ///< why the record cannot be used (from its conversion), or ""
};

/// An item after the record checks: `problem` empty if it may be used. `frame` may be a cleaned
/// copy (invalid points dropped).
struct CheckedItem {
  IngestItem item;
  std::string problem;
  double begin = 0, end = 0;  ///< [UNIX s] its time span (a frame: its points)
  std::size_t dropped = 0;    ///< invalid points dropped from the frame
  bool ok() const { return problem.empty(); }
};

/// The per-record checks, once per record of a stream: IMU samples finite and in time order;
/// clouds non-empty, without invalid points (or with them dropped: [input] drop_invalid_points),
/// in time order and not overlapping; a cloud with Doppler zero on every point is held until
/// the IMU around it is known and passes only if the IMU shows rest. Items come out in input
/// order except that clouds held for that wait (IMU samples pass them).
///
/// One IMU sample of look-ahead: each IMU sample is held until the next one arrives (or the
/// input ends). A held sample whose successor is later than the sample before it and earlier
/// than the held one by more than that interval was stamped ahead of its stream (a glitch of the
/// clock, the stream going on on its own): it comes out as an ignored observation (Kind::Other,
/// `what` naming the record and how far ahead it was; stampJumps() counts them), never as a sample,
/// so the window neither closes at it nor loses the samples after it. A stream that continues from
/// the new stamp is a gap for the estimator to judge.
///
/// The extrinsics of a rawlog (with [extrinsics] from_sensor_pose): every cloud's sensorPose
/// relative to the IMU's, whatever the order of the records (a cloud before the first IMU sample
/// waits for it). The first cloud's sets them; every later cloud must give the same (a record
/// that gives another, or a sensorPose whose rotation is not a rotation, is a bad record), and
/// every IMU sample the same sensorPose as the first.
class RecordChecker {
 public:
  explicit RecordChecker(const AppConfig& config);
  void push(IngestItem item, std::vector<CheckedItem>& out);
  /// End of the input: decides the held clouds with the IMU there is.
  void finish(std::vector<CheckedItem>& out);
  std::size_t invalidPointsDropped() const { return dropped_; }
  /// IMU samples dropped as stamped ahead of their stream (see above).
  std::size_t stampJumps() const { return stamp_jumps_; }
  /// The LiDAR pose in the body frame the clouds declare, once the first good cloud set it.
  const std::optional<Extrinsics>& declaredExtrinsics() const { return extrinsics_; }

 private:
  void resolve(bool force, std::vector<CheckedItem>& out);
  /// The checks of one record (push() without the IMU look-ahead).
  void check(IngestItem item, std::vector<CheckedItem>& out);
  /// Hands on the held IMU sample and what came after it.
  void releaseHeldImu(std::vector<CheckedItem>& out);
  /// The held IMU sample stamped ahead (the next is at next_t): dropped, as an ignored record.
  void dropHeldImu(double next_t, std::vector<CheckedItem>& out);
  /// The cloud's extrinsics from its sensorPose and the IMU's (identity when no IMU sample came),
  /// checked against the rule (see above).
  void checkExtrinsics(CheckedItem& c);

  InputParams input_;
  bool from_sensor_pose_ = true;
  std::optional<Extrinsics> imu_pose_;  ///< the first IMU sample's sensorPose
  std::size_t imu_pose_record_ = 0;
  std::optional<Extrinsics> extrinsics_;  ///< the rule: the first good cloud's
  std::size_t extrinsics_record_ = 0;
  input::RestParams rest_;
  std::optional<ImuSample> last_imu_;
  std::optional<double> last_stamp_, last_end_;
  struct Held {
    CheckedItem c;
    bool zero_doppler = false;    ///< waits for the IMU around it
    bool needs_imu_pose = false;  ///< its extrinsics wait for the first IMU sample's sensorPose
  };
  std::deque<ImuSample> recent_imu_;  ///< for the rest test of held clouds
  std::deque<Held> held_;             ///< clouds waiting, in order (the first for the IMU)
  std::size_t dropped_ = 0;
  std::optional<CheckedItem> held_imu_;   ///< the IMU look-ahead: the last good sample
  std::vector<CheckedItem> after_held_;   ///< items that came after it, in order
  std::optional<ImuSample> before_held_;  ///< the sample handed on before it
  std::size_t stamp_jumps_ = 0;
};

/// A record that failed a check, as a session keeps it.
struct RecordProblem {
  std::size_t record = 0;
  double begin = 0, end = 0;  ///< [UNIX s]
  std::string what;
};

/// One initialization: the checked items from its start on, into a FreeInit estimator. The first
/// kWindowImuCheckSamples IMU samples (and the clouds between them) are held back until the
/// rate and unit checks pass and, with [extrinsics] from_sensor_pose, the first cloud gave the
/// extrinsics; then everything goes to the estimator as it comes.
class InitSession {
 public:
  /// `source` names the input in messages (a file name, "live stream"); `from_file`: it is a
  /// rawlog (false: a stream), for the hints of endOfDataReason().
  InitSession(const AppConfig& config, std::string source, bool from_file = true);

  void push(const CheckedItem& c);
  /// End of the input: closes a window still open with what is there.
  void finish();
  /// The input cannot be read on (e.g. a corrupt record): fails unless done.
  void fail(const std::string& message);

  /// The estimator is ready, or the session failed (errors() not empty).
  bool done() const { return failed_ || ready(); }
  bool ready() const { return estimator_ && estimator_->ready(); }
  bool failed() const { return failed_; }
  /// The result; status NotEnoughData until ready(). The first call after ready() builds the map.
  const InitResult& result() const;
  /// The result without its map (FreeInit::resultBeforeMap): final at ready().
  const InitResult& resultBeforeMap() const;
  /// The extrinsics in use (from the INI or, once a cloud arrived, from its declared pose).
  const Extrinsics& extrinsics() const { return config_.core.extrinsics; }

  /// Messages "<source>: record N: what". Errors: the stretch checks, bad records inside the
  /// window, and (after finish() without a state) the bad records that may explain it.
  const std::vector<std::string>& errors() const { return errors_; }
  /// Bad records outside the window, ignored observations, dropped points.
  std::vector<std::string> warnings() const;
  /// Why there is no window, for a file that ended (no IMU, no cloud, shorter than the window),
  /// in the offline app's words; "" if there is nothing to say.
  std::string endOfDataReason() const;

  /// [UNIX s] the window (result().trajectory.front().t .. result().state.timestamp; before a
  /// state: the data fed so far).
  std::pair<double, double> window() const;

  std::size_t imuCount() const { return imu_count_; }
  std::size_t frameCount() const { return frame_count_; }
  std::optional<double> firstTime() const { return first_t_; }
  std::optional<double> lastTime() const { return last_t_; }

 private:
  void checkImu();
  void feed();
  void classify(const RecordProblem& p);
  void onReady();

  AppConfig config_;
  std::string source_;
  bool from_file_ = true;
  std::unique_ptr<FreeInit> estimator_;
  bool extrinsics_known_ = false;
  bool imu_checked_ = false;
  bool failed_ = false;
  bool classified_ = false;  ///< problems were sorted into errors and warnings
  std::size_t imu_check_samples_ = 0;
  std::vector<ImuSample> held_imu_;
  std::size_t first_imu_record_ = 0;
  std::vector<std::pair<std::size_t, std::shared_ptr<const LidarFrame>>> held_frames_;
  std::vector<RecordProblem> problems_;
  std::vector<std::string> errors_, outside_;
  std::map<std::string, std::size_t> ignored_;  ///< what -> count
  std::size_t dropped_points_ = 0;
  std::optional<double> first_t_, last_t_;
  std::optional<double> first_frame_t_;
  std::size_t first_frame_record_ = 0, imu_after_first_frame_ = 0;
  double first_frame_begin_ = 0, first_frame_end_ = 0;  ///< [UNIX s] its points' span
  std::optional<double> last_imu_t_;
  std::size_t imu_count_ = 0, frame_count_ = 0;
  InitResult empty_;
};

}  // namespace freeinit::app_support
