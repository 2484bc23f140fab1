#include <freeinit/app_support/ingest.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace freeinit::app_support {

// ---------------------------------------------------------------------------------------------
// RecordChecker

RecordChecker::RecordChecker(const AppConfig& config)
    : input_(config.input),
      from_sensor_pose_(config.extrinsics.from_sensor_pose),
      rest_(input::restParams(config.core)) {}

namespace {

// Sensor poses are equal when they come from one calibration: stored as doubles they agree to
// their last bits; 1e-6 rad and 1e-6 m leave room for a tool that recomputes them per record.
constexpr double kPoseAngleTolerance = 1e-6, kPosePositionTolerance = 1e-6;

double angleBetween(const Mat3& a, const Mat3& b) {
  const double c = 0.5 * ((a.transpose() * b).trace() - 1.0);
  return std::acos(std::clamp(c, -1.0, 1.0));
}

bool samePose(const Extrinsics& a, const Extrinsics& b) {
  return angleBetween(a.R_bl, b.R_bl) <= kPoseAngleTolerance &&
         (a.p_bl - b.p_bl).norm() <= kPosePositionTolerance;
}

bool isRotation(const Mat3& R) {
  return R.allFinite() && (R.transpose() * R - Mat3::Identity()).norm() < 1e-6 &&
         R.determinant() > 0;
}

std::string describePose(const Extrinsics& e) {
  std::ostringstream os;
  const Eigen::AngleAxisd aa(e.R_bl);
  os << std::setprecision(6) << "p_bl = (" << e.p_bl.x() << ", " << e.p_bl.y() << ", " << e.p_bl.z()
     << ") m, rotation " << aa.angle() * 180.0 / M_PI << " deg";
  return os.str();
}

}  // namespace

void RecordChecker::checkExtrinsics(CheckedItem& c) {
  IngestItem& it = c.item;
  if (!it.frame_extrinsics) {
    if (!isRotation(it.sensor_pose->R_bl)) {
      c.problem = "its sensorPose is not a rigid pose (its rotation is not a rotation matrix)";
      return;
    }
    // The LiDAR in the body frame: the IMU's pose inverted, composed with the cloud's.
    Extrinsics e;
    const Extrinsics imu = imu_pose_.value_or(Extrinsics{});
    e.R_bl = imu.R_bl.transpose() * it.sensor_pose->R_bl;
    e.p_bl = imu.R_bl.transpose() * (it.sensor_pose->p_bl - imu.p_bl);
    it.frame_extrinsics = e;
  }
  if (!isRotation(it.frame_extrinsics->R_bl)) {
    c.problem = "its extrinsics are not a rigid pose (the rotation is not a rotation matrix)";
    return;
  }
  if (!extrinsics_) {
    extrinsics_ = it.frame_extrinsics;
    extrinsics_record_ = it.record;
  } else if (!samePose(*extrinsics_, *it.frame_extrinsics)) {
    c.problem = "its sensorPose gives the LiDAR another pose in the IMU frame (" +
                describePose(*it.frame_extrinsics) + ") than record " +
                std::to_string(extrinsics_record_) + " does (" + describePose(*extrinsics_) +
                "): one recording has one calibration";
  }
}

void RecordChecker::push(IngestItem item, std::vector<CheckedItem>& out) {
  // The held IMU sample's stamp jumped ahead when the next one is earlier than it, by more
  // than it is later than the one before it: the stream goes on on its clock; the held one is
  // dropped. (A next one equal to the held one, or a little before it, is the next one's fault:
  // a bad record, as before.)
  if (item.kind == IngestItem::Kind::Imu && item.problem.empty() && held_imu_ && before_held_ &&
      std::isfinite(item.imu.t) && item.imu.t > before_held_->t &&
      held_imu_->item.imu.t - item.imu.t > item.imu.t - before_held_->t)
    dropHeldImu(item.imu.t, out);
  std::vector<CheckedItem> checked;
  check(std::move(item), checked);
  for (CheckedItem& c : checked) {
    if (c.item.kind == IngestItem::Kind::Imu && c.ok()) {
      releaseHeldImu(out);
      held_imu_ = std::move(c);
    } else if (held_imu_) {
      after_held_.push_back(std::move(c));  // input order: after the held sample
    } else {
      out.push_back(std::move(c));
    }
  }
}

void RecordChecker::releaseHeldImu(std::vector<CheckedItem>& out) {
  if (!held_imu_) return;
  before_held_ = held_imu_->item.imu;
  out.push_back(std::move(*held_imu_));
  held_imu_.reset();
  for (CheckedItem& c : after_held_) out.push_back(std::move(c));
  after_held_.clear();
}

void RecordChecker::dropHeldImu(double next_t, std::vector<CheckedItem>& out) {
  CheckedItem& h = *held_imu_;
  const double t = h.item.imu.t;
  std::ostringstream what;
  what << "IMU record " << h.item.record << " stamped " << std::setprecision(6) << t - next_t
       << " s ahead of its stream (dropped)";
  // Taken back: the next sample is checked against the one before it.
  last_imu_ = before_held_;
  if (!recent_imu_.empty() && recent_imu_.back().t == t) recent_imu_.pop_back();
  h.item.kind = IngestItem::Kind::Other;
  h.item.what = what.str();
  ++stamp_jumps_;
  // Not released: before_held_ stays the sample before it.
  out.push_back(std::move(h));
  held_imu_.reset();
  for (CheckedItem& c : after_held_) out.push_back(std::move(c));
  after_held_.clear();
}

void RecordChecker::check(IngestItem item, std::vector<CheckedItem>& out) {
  CheckedItem c;
  c.problem = std::move(item.problem);
  c.begin = c.end = item.t;
  c.item = std::move(item);
  IngestItem& it = c.item;

  if (it.kind == IngestItem::Kind::Imu) {
    if (c.ok()) {
      if (auto p = input::imuSampleProblem(it.imu, last_imu_ ? &*last_imu_ : nullptr))
        c.problem = *p;
    }
    if (c.ok() && from_sensor_pose_ && it.sensor_pose) {
      if (!isRotation(it.sensor_pose->R_bl)) {
        c.problem = "its sensorPose is not a rigid pose (its rotation is not a rotation matrix)";
      } else if (!imu_pose_) {
        imu_pose_ = it.sensor_pose;
        imu_pose_record_ = it.record;
      } else if (!samePose(*imu_pose_, *it.sensor_pose)) {
        c.problem = "its sensorPose (" + describePose(*it.sensor_pose) +
                    ") differs from the first IMU sample's (record " +
                    std::to_string(imu_pose_record_) + ": " + describePose(*imu_pose_) +
                    "): the IMU does not move on the platform";
      }
    }
    if (c.ok()) {
      last_imu_ = it.imu;
      recent_imu_.push_back(it.imu);
      // Keep what the rest test of a held cloud may need, and half a second for the next one
      // (from the sample held before this one: this one's stamp may have jumped ahead).
      const double newest = held_imu_ ? held_imu_->item.imu.t : it.imu.t;
      const double keep_from =
          held_.empty() ? newest - 0.5
                        : std::min(newest - 0.5, held_.front().c.begin - input::kRestMargin);
      while (!recent_imu_.empty() && recent_imu_.front().t < keep_from) recent_imu_.pop_front();
    }
    out.push_back(std::move(c));
    resolve(false, out);
    return;
  }
  if (it.kind != IngestItem::Kind::Frame) {
    out.push_back(std::move(c));
    return;
  }

  bool zero_doppler = false;
  if (c.ok() && !it.frame) c.problem = "no point cloud";
  if (c.ok()) {
    const LidarFrame& f = *it.frame;
    const auto bad = static_cast<std::size_t>(
        std::count_if(f.points.begin(), f.points.end(), input::invalidPoint));
    if (f.points.empty()) {
      c.problem = "empty point cloud";
    } else if (bad > 0 && !input_.drop_invalid_points) {
      c.problem = std::to_string(bad) + " of " + std::to_string(f.points.size()) +
                  " points have NaN or infinite coordinates, Doppler or time (set [input] "
                  "drop_invalid_points = true to drop them)";
    } else if (bad > 0) {
      auto clean = std::make_shared<LidarFrame>();
      clean->stamp = f.stamp;
      clean->points.reserve(f.points.size() - bad);
      for (const auto& p : f.points)
        if (!input::invalidPoint(p)) clean->points.push_back(p);
      dropped_ += bad;
      c.dropped = bad;
      if (clean->points.empty())
        c.problem = "no valid point left in the cloud";
      else
        it.frame = std::move(clean);
    }
  }
  if (c.ok()) {
    const LidarFrame& f = *it.frame;
    if (auto p = input::frameOrderProblem(f, last_stamp_, last_end_)) c.problem = *p;
  }
  // A rawlog cloud's extrinsics need the IMU's sensorPose: before the first IMU sample it waits.
  const bool needs_imu_pose =
      c.ok() && from_sensor_pose_ && !it.frame_extrinsics && it.sensor_pose && !imu_pose_;
  if (c.ok() && from_sensor_pose_ && !needs_imu_pose && (it.frame_extrinsics || it.sensor_pose))
    checkExtrinsics(c);
  if (c.ok()) {
    const input::FrameSpan span = input::frameSpan(*it.frame);
    c.begin = span.begin;
    c.end = span.end;
    last_stamp_ = it.frame->stamp;
    last_end_ = span.end;
    // Binned Doppler reads zero everywhere at rest and moving slowly: nothing to check then.
    zero_doppler = !(input_.doppler_resolution > 0) && input::dopplerAllZero(it.frame->points);
  } else if (it.frame && !it.frame->points.empty()) {
    // A bad cloud: its span from the finite time offsets, for telling in or out of a window.
    double lo = 0, hi = 0;
    bool any = false;
    for (const auto& p : it.frame->points) {
      if (!std::isfinite(p.time_offset)) continue;
      lo = any ? std::min<double>(lo, p.time_offset) : p.time_offset;
      hi = any ? std::max<double>(hi, p.time_offset) : p.time_offset;
      any = true;
    }
    c.begin = it.t + lo;
    c.end = it.t + hi;
  }
  if (c.ok() && (zero_doppler || needs_imu_pose || !held_.empty())) {
    held_.push_back({std::move(c), zero_doppler, needs_imu_pose});
  } else {
    out.push_back(std::move(c));
  }
  resolve(false, out);
}

void RecordChecker::resolve(bool force, std::vector<CheckedItem>& out) {
  while (!held_.empty()) {
    Held& h = held_.front();
    if (h.needs_imu_pose) {
      if (!force && !imu_pose_) return;  // no IMU sample yet
      checkExtrinsics(h.c);
      h.needs_imu_pose = false;
    }
    if (h.zero_doppler && h.c.ok()) {
      const double from = h.c.begin - input::kRestMargin, until = h.c.end + input::kRestMargin;
      if (!force && !(last_imu_ && last_imu_->t > until)) return;  // the IMU is not there yet
      std::vector<ImuSample> around;
      for (const auto& s : recent_imu_)
        if (s.t >= from && s.t <= until) around.push_back(s);
      if (auto p = input::zeroDopplerProblem(around, rest_)) h.c.problem = *p;
    }
    out.push_back(std::move(h.c));
    held_.pop_front();
  }
}

void RecordChecker::finish(std::vector<CheckedItem>& out) {
  releaseHeldImu(out);
  resolve(true, out);
}

// ---------------------------------------------------------------------------------------------
// InitSession

InitSession::InitSession(const AppConfig& config, std::string source, bool from_file)
    : config_(config), source_(std::move(source)), from_file_(from_file) {
  config_.core.validate();
  extrinsics_known_ = !config_.extrinsics.from_sensor_pose;
  imu_check_samples_ = input::kWindowImuCheckSamples;
}

const InitResult& InitSession::result() const { return estimator_ ? estimator_->result() : empty_; }
const InitResult& InitSession::resultBeforeMap() const {
  return estimator_ ? estimator_->resultBeforeMap() : empty_;
}

void InitSession::checkImu() {
  const auto& in = config_.input;
  const std::string at = source_ + ": record " + std::to_string(first_imu_record_) + ": ";
  std::optional<std::string> problem = input::imuRateProblem(held_imu_, in.min_imu_rate);
  if (!problem) problem = input::accelUnitProblem(held_imu_, in.imu_accel_in_g);
  if (problem) {
    errors_.push_back(at + *problem);
    failed_ = true;
    return;
  }
  imu_checked_ = true;
}

void InitSession::feed() {
  if (failed_ || !imu_checked_ || !extrinsics_known_) return;
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

void InitSession::push(const CheckedItem& c) {
  if (done()) return;
  const IngestItem& it = c.item;
  if (it.kind == IngestItem::Kind::Other) {
    if (!c.ok()) {
      problems_.push_back({it.record, c.begin, c.end, c.problem});
    } else if (!it.what.empty()) {
      ++ignored_[it.what];
    }
    return;
  }
  if (!c.ok()) {
    problems_.push_back({it.record, c.begin, c.end, c.problem});
    return;
  }
  if (!first_t_) first_t_ = c.begin;
  last_t_ = std::max(last_t_.value_or(c.end), c.end);
  try {
    if (it.kind == IngestItem::Kind::Imu) {
      ++imu_count_;
      last_imu_t_ = it.imu.t;
      if (first_frame_t_ && it.imu.t >= *first_frame_t_) ++imu_after_first_frame_;
      if (estimator_) {
        estimator_->addImu(it.imu);
      } else {
        if (held_imu_.empty()) first_imu_record_ = it.record;
        held_imu_.push_back(it.imu);
        if (!imu_checked_ && held_imu_.size() >= imu_check_samples_) checkImu();
        feed();
      }
    } else {
      ++frame_count_;
      dropped_points_ += c.dropped;
      if (!first_frame_t_) {
        first_frame_t_ = it.frame->stamp;
        first_frame_record_ = it.record;
        first_frame_begin_ = c.begin;
        first_frame_end_ = c.end;
      }
      if (!extrinsics_known_) {
        if (it.frame_extrinsics) config_.core.extrinsics = *it.frame_extrinsics;
        extrinsics_known_ = true;
      }
      if (estimator_) {
        estimator_->addFrame(it.frame);
      } else {
        held_frames_.emplace_back(held_imu_.size(), it.frame);
        feed();
      }
    }
  } catch (const std::invalid_argument& e) {
    // The record checks make this unreachable; kept so that no input can crash a session.
    errors_.push_back(source_ + ": record " + std::to_string(it.record) + ": " + e.what());
    failed_ = true;
    return;
  }
  if (ready()) onReady();
}

std::pair<double, double> InitSession::window() const {
  const InitResult& r = resultBeforeMap();
  if (ready() && r.state.ok() && !r.trajectory.empty())
    return {r.trajectory.front().t, r.state.timestamp};
  if (first_t_) return {*first_t_, *last_t_};
  return {-std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
}

void InitSession::classify(const RecordProblem& p) {
  const auto [a, b] = window();
  const std::string msg = source_ + ": record " + std::to_string(p.record) + ": " + p.what;
  if (p.begin <= b && p.end >= a) {
    errors_.push_back(msg);
    failed_ = true;
  } else {
    outside_.push_back(msg + " (not used: outside the initialization window)");
  }
}

void InitSession::onReady() {
  if (classified_) return;
  classified_ = true;
  for (const auto& p : problems_) classify(p);
}

void InitSession::finish() {
  if (failed_ || classified_) return;
  if (!imu_checked_) {
    if (held_imu_.empty())
      imu_checked_ = true;  // nothing to check: the estimator says there is not enough data
    else
      checkImu();
  }
  if (failed_) return;
  extrinsics_known_ = true;  // no cloud came: the configured extrinsics
  feed();
  if (estimator_) estimator_->finish();
  onReady();
}

void InitSession::fail(const std::string& message) {
  if (done()) return;
  errors_.push_back(message);
  failed_ = true;
}

std::vector<std::string> InitSession::warnings() const {
  std::vector<std::string> w;
  for (const auto& [what, n] : ignored_)
    w.push_back("ignored " + std::to_string(n) + " observation(s) of " + what);
  if (dropped_points_ > 0)
    w.push_back("dropped " + std::to_string(dropped_points_) + " NaN/inf points");
  w.insert(w.end(), outside_.begin(), outside_.end());
  return w;
}

std::string InitSession::endOfDataReason() const {
  std::string others;
  for (const auto& [what, n] : ignored_)
    others += (others.empty() ? "" : ", ") + std::to_string(n) + " " + what;
  const auto& in = config_.input;
  // MRPT tools that did not load the plugin silently stop at the first Doppler cloud: a copy
  // made that way holds only what came before it.
  const std::string plugin_hint =
      from_file_ ? " (a rawlog copied by an MRPT tool without the freeinit plugin keeps only the "
                   "records before the first Doppler cloud: give the tool -p "
                   "libfreeinit_mrpt_plugins.so)"
                 : "";
  if (imu_count_ == 0 && frame_count_ == 0)
    return source_ + ": neither a CObservationIMU '" + in.imu_label +
           "' nor a CObservationPointCloud '" + in.lidar_label +
           "' ([input] imu_label, lidar_label); " +
           (others.empty() ? std::string("nothing else either") : "other observations: " + others);
  if (imu_count_ == 0)
    return source_ + ": no CObservationIMU with sensorLabel '" + in.imu_label +
           "' ([input] imu_label); the input holds " + std::to_string(frame_count_) +
           (frame_count_ == 1 ? " point cloud '" : " point clouds '") + in.lidar_label + "'" +
           (others.empty() ? std::string(" and nothing else") : " and " + others);
  if (frame_count_ == 0)
    return source_ + ": no CObservationPointCloud with sensorLabel '" + in.lidar_label +
           "' ([input] lidar_label); the input holds only " + std::to_string(imu_count_) +
           (imu_count_ == 1 ? " IMU sample '" : " IMU samples '") + in.imu_label + "'" +
           (others.empty() ? "" : " and " + others) + plugin_hint;
  if (imu_count_ < 2)
    return source_ + ": record " + std::to_string(first_imu_record_) + ": a single IMU sample";
  const double window_s = config_.core.window.duration;
  std::ostringstream window;
  window << window_s;
  // The IMU goes on for a window after the first cloud's stamp, yet its points start later
  // than a sweep after it (kLatePoints), beyond the IMU data or too late in it for a window:
  // their times, not the recording's length.
  constexpr double kLatePoints = 0.1;  // [s] a LiDAR sweep
  if (first_frame_t_ && last_imu_t_ && *last_imu_t_ - *first_frame_t_ >= window_s &&
      first_frame_begin_ - *first_frame_t_ > kLatePoints &&
      first_frame_begin_ + window_s > *last_imu_t_) {
    std::ostringstream os;
    os << std::setprecision(4) << source_ << ": record " << first_frame_record_
       << ": its points are timed " << first_frame_begin_ - *first_frame_t_ << " to "
       << first_frame_end_ - *first_frame_t_
       << " s after the cloud's stamp, and the IMU samples end " << *last_imu_t_ - *first_frame_t_
       << " s after it: no " << window.str()
       << " s window ([window] duration) fits after the first point (point time offsets in "
          "another unit, or counted from another instant than the stamp?)";
    return os.str();
  }
  std::ostringstream covered;
  covered << std::setprecision(3)
          << (last_imu_t_ && first_frame_t_ ? *last_imu_t_ - *first_frame_t_ : 0.0);
  return source_ + ": " + (from_file_ ? "recording" : "stream") +
         " shorter than the window: " + covered.str() + " s (" +
         std::to_string(imu_after_first_frame_) +
         " IMU samples) after the first point cloud (record " +
         std::to_string(first_frame_record_) + "), the window needs " + window.str() +
         " s ([window] duration)";
}

}  // namespace freeinit::app_support
