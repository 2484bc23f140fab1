#include <freeinit/accel_unit.h>
#include <freeinit/bags/import_stream.h>
#include <freeinit/io/number_format.h>

#include <algorithm>
#include <cmath>
#include <ostream>
#include <utility>

namespace freeinit::bags {

double TopicSummary::meanRate() const {
  return imported > 1 && last > first ? static_cast<double>(imported - 1) / (last - first) : 0;
}

void BagSummary::print(std::ostream& out) const {
  out << (kind.empty() ? "Bag" : "Recording") << " " << file
      << (kind.empty() ? "" : " (" + kind + ")") << ":\n";
  for (const TopicSummary* t : {&imu, &lidar}) {
    out << "  " << t->topic << " (" << t->type << "): " << t->in_bag << " messages, " << t->imported
        << " imported";
    if (t->skipped() > 0) {
      out << ", skipped " << t->out_of_order << " out of order, " << t->duplicated
          << " duplicated stamps, " << t->unusable << " unusable";
      if (t->untriggered > 0) out << ", " << t->untriggered << " without a trigger";
    }
    out << "\n";
    if (t->imported == 0) continue;
    out << "    " << formatFixed(t->first, 6) << " .. " << formatFixed(t->last, 6) << " ("
        << formatFixed(t->last - t->first, 3) << " s), " << formatFixed(t->meanRate(), 2)
        << " Hz mean, " << formatFixed(t->median_interval > 0 ? 1.0 / t->median_interval : 0.0, 2)
        << " Hz nominal; " << t->gaps << " gap(s) > " << gap_factor << "x the nominal interval";
    if (t->gaps > 0)
      out << ", largest " << formatFixed(t->largest_gap, 4) << " s ending at "
          << formatFixed(t->largest_gap_at, 6);
    out << "\n";
  }
  if (!trigger.topic.empty()) {
    out << "  scan stamps from " << trigger.topic
        << " (std_msgs/Header, matched by seq): " << trigger.in_bag << " triggers, " << trigger.used
        << " used, " << trigger.in_bag - trigger.used << " without a cloud";
    if (trigger.repeated_seq > 0) out << ", " << trigger.repeated_seq << " with a repeated seq";
    out << "; clouds recorded " << formatFixed(trigger.median_bag_delay, 6)
        << " s (median, bag time - trigger stamp) after their trigger\n";
  }
  out << "  points: " << points << " imported";
  if (invalid_points > 0) out << ", " << invalid_points << " NaN/inf points dropped";
  out << "\n  mean specific force over the first IMU samples: " << formatFixed(accel_mean_norm, 3)
      << " m/s^2\n";
  for (const auto& o : other_topics) out << "  not imported: " << o << "\n";
  for (const auto& w : warnings) out << "  warning: " << w << "\n";
}

bool ImportStream::TopicState::accept(double t) {
  if (t <= 0) {
    ++summary.unusable;
    return false;
  }
  if (last >= 0 && t <= last) {
    ++(t == last ? summary.duplicated : summary.out_of_order);
    return false;
  }
  last = t;
  return true;
}

void ImportStream::TopicState::finish(double gap_factor) {
  TopicSummary& s = summary;
  s.imported = stamps.size();
  if (stamps.empty()) return;
  s.first = stamps.front();
  s.last = stamps.back();
  if (stamps.size() < 2) return;
  std::vector<double> dt(stamps.size() - 1);
  for (std::size_t i = 1; i < stamps.size(); ++i) dt[i - 1] = stamps[i] - stamps[i - 1];
  std::vector<double> sorted = dt;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(dt.size() / 2),
                   sorted.end());
  s.median_interval = sorted[dt.size() / 2];
  s.gaps = 0;
  s.largest_gap = 0;
  for (std::size_t i = 0; i < dt.size(); ++i) {
    if (dt[i] > gap_factor * s.median_interval) ++s.gaps;
    if (dt[i] > s.largest_gap) {
      s.largest_gap = dt[i];
      s.largest_gap_at = stamps[i + 1];
    }
  }
}

ImportStream::ImportStream(const BagImportConfig& config, BagReadCallbacks callbacks)
    : config_(config), cb_(std::move(callbacks)) {}

void ImportStream::emit(std::map<Key, Pending>::iterator it) {
  const auto& [t, kind, seq] = it->first;
  written_up_to_ = t;
  if (kind == 0) {
    cb_.imu(it->second.imu);
  } else {
    cb_.frame(std::move(it->second.frame));
  }
  buffer_.erase(it);
}

void ImportStream::push(double t, int kind, Pending&& p, const std::string& where) {
  if (t < written_up_to_)
    throw BagError(where + ": stamped " + formatFixed(t, 9) + ", but messages up to " +
                   formatFixed(written_up_to_, 9) +
                   " were already written: it arrived more than reorder_window = " +
                   formatFixed(config_.reorder_window, 3) + " s late; increase reorder_window");
  buffer_.emplace(Key{t, kind, arrival_++}, std::move(p));
  newest_ = std::max(newest_, t);
  while (!buffer_.empty() && std::get<0>(buffer_.begin()->first) < newest_ - config_.reorder_window)
    emit(buffer_.begin());
}

void ImportStream::checkUnit(const std::string& where) {
  unit_checked_ = true;
  accel_mean_norm_ = (accel_sum_ / accel_n_).norm();
  const double g = accel_mean_norm_;
  const AccelUnitMismatch unit = accelUnitMismatch(g, config_.imu_accel_in_g);
  if (unit == AccelUnitMismatch::kDataInG)
    throw BagError(where + ": the mean specific force of the first " + std::to_string(accel_n_) +
                   " IMU samples is " + formatFixed(g, 3) +
                   ": the IMU reports g, not m/s^2 (set imu_accel_unit = g)");
  if (unit == AccelUnitMismatch::kDataInMs2)
    throw BagError(where + ": imu_accel_unit = g, but the first " + std::to_string(accel_n_) +
                   " IMU samples average " + formatFixed(g, 2) +
                   " m/s^2 after conversion: the IMU reports m/s^2");
}

void ImportStream::imu(ImuSample sample, const std::string& where) {
  sample.accel *= config_.imu_accel_in_g ? kGravity : 1.0;
  if (!sample.gyro.allFinite() || !sample.accel.allFinite()) {
    ++imu_.summary.unusable;
    return;
  }
  if (!imu_.accept(sample.t)) return;
  if (accel_n_ < config_.unit_check_samples) {
    accel_sum_ += sample.accel;
    if (++accel_n_ == config_.unit_check_samples) checkUnit(where);
  }
  imu_.stamps.push_back(sample.t);
  Pending p;
  p.imu = sample;
  push(sample.t, 0, std::move(p), where);
}

void ImportStream::frame(LidarFrame&& frame, double scan_stamp, const std::string& where) {
  frame.stamp = scan_stamp + config_.lidar_time_offset;
  if (frame.points.empty() || scan_stamp == 0) {
    ++lidar_.summary.unusable;
    return;
  }
  if (!lidar_.accept(frame.stamp)) return;
  points_ += frame.points.size();
  lidar_.stamps.push_back(frame.stamp);
  const double t = frame.stamp;
  Pending p;
  p.frame = std::move(frame);
  push(t, 1, std::move(p), where);
}

void ImportStream::finish(const std::string& where) {
  if (accel_n_ > 0 && !unit_checked_) checkUnit(where);
  while (!buffer_.empty()) emit(buffer_.begin());
}

void ImportStream::restart() {
  buffer_.clear();
  written_up_to_ = -1;
  newest_ = -1;
  imu_.last = -1;
  lidar_.last = -1;
}

void ImportStream::summarize(BagSummary& summary, std::size_t invalid_points) {
  imu_.finish(config_.gap_factor);
  lidar_.finish(config_.gap_factor);
  auto merge = [](TopicSummary& out, const TopicSummary& in) {
    const TopicSummary keep = out;
    out = in;
    out.topic = keep.topic;
    out.type = keep.type;
    out.in_bag = keep.in_bag;
  };
  merge(summary.imu, imu_.summary);
  merge(summary.lidar, lidar_.summary);
  summary.points = points_;
  summary.invalid_points = invalid_points;
  summary.accel_mean_norm = accel_mean_norm_;
  summary.gap_factor = config_.gap_factor;
  for (const auto* t : {&summary.imu, &summary.lidar})
    if (t->imported == 0)
      throw BagError(summary.file + ": no usable message on " + t->topic + " (" +
                     std::to_string(t->skipped()) + " skipped)");
}

}  // namespace freeinit::bags
