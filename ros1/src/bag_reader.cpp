#include <freeinit/accel_unit.h>
#include <freeinit/ros1/bag_guard.h>
#include <freeinit/ros1/bag_reader.h>
#include <freeinit/ros1/cloud_codec.h>
#include <ros/serialization.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_msgs/Header.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <map>
#include <ostream>
#include <sstream>
#include <tuple>

namespace freeinit::ros1 {
namespace {

std::string fmt(double t, int precision = 9) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(precision) << t;
  return os.str();
}

// One message waiting in the reorder buffer, ordered by (stamp, IMU before LiDAR, arrival).
struct Pending {
  ImuSample imu;
  LidarFrame frame;
};
using PendingKey = std::tuple<double, int, std::size_t>;

// Per-topic bookkeeping while reading.
struct TopicState {
  TopicSummary summary;
  std::vector<double> stamps;  // imported stamps, for rates and gaps
  double last = -1;            // last accepted stamp

  // False (and counted) when `t` does not increase within the topic.
  bool accept(double t) {
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

  void finish(double gap_factor) {
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
    for (std::size_t i = 0; i < dt.size(); ++i) {
      if (dt[i] > gap_factor * s.median_interval) ++s.gaps;
      if (dt[i] > s.largest_gap) {
        s.largest_gap = dt[i];
        s.largest_gap_at = stamps[i + 1];
      }
    }
  }
};

void checkConnection(const std::string& file, const rosbag::ConnectionInfo& c,
                     const std::string& type, const std::string& md5) {
  if (c.datatype != type)
    throw BagError(file + ": topic " + c.topic + " has type " + c.datatype + ", expected " + type);
  if (c.md5sum != md5)
    throw BagError(file + ": topic " + c.topic + " (" + type + ") was recorded with another " +
                   "message definition (md5 " + c.md5sum + ", expected " + md5 + ")");
}

// Deserializes one message through `buf` after checking its serialized lengths: roscpp sizes
// strings and vectors from their declared lengths before it looks at the bytes.
template <class T>
void readMessage(const rosbag::MessageInstance& m, RosMessage type, std::vector<std::uint8_t>& buf,
                 T& msg) {
  const std::uint32_t n = m.size();
  buf.resize(n);
  ros::serialization::OStream out(buf.data(), n);
  m.write(out);
  checkSerialized(type, buf.data(), n);
  ros::serialization::IStream in(buf.data(), n);
  ros::serialization::deserialize(in, msg);
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

}  // namespace

double TopicSummary::meanRate() const {
  return imported > 1 && last > first ? static_cast<double>(imported - 1) / (last - first) : 0;
}

void BagSummary::print(std::ostream& out) const {
  out << "Bag " << file << ":\n";
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
    out << "    " << fmt(t->first, 6) << " .. " << fmt(t->last, 6) << " ("
        << fmt(t->last - t->first, 3) << " s), " << fmt(t->meanRate(), 2) << " Hz mean, "
        << fmt(t->median_interval > 0 ? 1.0 / t->median_interval : 0.0, 2) << " Hz nominal; "
        << t->gaps << " gap(s) > " << gap_factor << "x the nominal interval";
    if (t->gaps > 0)
      out << ", largest " << fmt(t->largest_gap, 4) << " s ending at " << fmt(t->largest_gap_at, 6);
    out << "\n";
  }
  if (!trigger.topic.empty()) {
    out << "  scan stamps from " << trigger.topic
        << " (std_msgs/Header, matched by seq): " << trigger.in_bag << " triggers, " << trigger.used
        << " used, " << trigger.in_bag - trigger.used << " without a cloud";
    if (trigger.repeated_seq > 0) out << ", " << trigger.repeated_seq << " with a repeated seq";
    out << "; clouds recorded " << fmt(trigger.median_bag_delay, 6)
        << " s (median, bag time - trigger stamp) after their trigger\n";
  }
  out << "  points: " << points << " imported";
  if (invalid_points > 0) out << ", " << invalid_points << " NaN/inf points dropped";
  out << "\n  mean specific force over the first IMU samples: " << fmt(accel_mean_norm, 3)
      << " m/s^2\n";
  for (const auto& o : other_topics) out << "  not imported: " << o << "\n";
}

BagSummary readBag(const std::string& path, const BagImportConfig& config,
                   const BagReadCallbacks& cb) {
  validate(config);
  // The structure first: librosbag trusts every length in the file.
  checkBagFile(path);
  rosbag::Bag bag;
  try {
    bag.open(path, rosbag::bagmode::Read);
  } catch (const std::exception& e) {
    throw BagError(path + ": cannot open as a ROS1 bag: " + e.what());
  }

  // Topics: both must exist with the right message type; list the others.
  const std::string imu_md5 = ros::message_traits::MD5Sum<sensor_msgs::Imu>::value();
  const std::string pc_md5 = ros::message_traits::MD5Sum<sensor_msgs::PointCloud2>::value();
  const std::string header_md5 = ros::message_traits::MD5Sum<std_msgs::Header>::value();
  const bool by_trigger = config.stamp_source == StampSource::kTrigger;
  TopicState imu_state, lidar_state;
  imu_state.summary.topic = config.imu_topic;
  lidar_state.summary.topic = config.lidar_topic;
  BagSummary summary;
  summary.file = path;
  summary.gap_factor = config.gap_factor;
  if (by_trigger) summary.trigger.topic = config.trigger_topic;
  std::vector<std::string> listing;
  try {
    rosbag::View all(bag);
    std::map<std::string, std::string> types;
    for (const rosbag::ConnectionInfo* c : all.getConnections()) {
      types[c->topic] = c->datatype;
      if (c->topic == config.imu_topic) checkConnection(path, *c, "sensor_msgs/Imu", imu_md5);
      if (c->topic == config.lidar_topic)
        checkConnection(path, *c, "sensor_msgs/PointCloud2", pc_md5);
      if (by_trigger && c->topic == config.trigger_topic)
        checkConnection(path, *c, "std_msgs/Header", header_md5);
    }
    for (const auto& [topic, type] : types) {
      const std::size_t n = rosbag::View(bag, rosbag::TopicQuery(topic)).size();
      const std::string line = topic + " (" + type + ", " + std::to_string(n) + " messages)";
      listing.push_back(line);
      if (topic == config.imu_topic) {
        imu_state.summary.type = type;
        imu_state.summary.in_bag = n;
      } else if (topic == config.lidar_topic) {
        lidar_state.summary.type = type;
        lidar_state.summary.in_bag = n;
      } else if (by_trigger && topic == config.trigger_topic) {
        summary.trigger.in_bag = n;
      } else {
        summary.other_topics.push_back(line);
      }
    }
  } catch (const BagError&) {
    throw;
  } catch (const std::exception& e) {
    throw BagError(path + ": cannot read the bag's index: " + e.what() + " (corrupt bag?)");
  }
  {
    auto all_topics = [&] {
      std::string s;
      for (const auto& l : listing) s += "\n  " + l;
      return s.empty() ? std::string(" none") : s;
    };
    if (listing.empty())
      throw BagError(path +
                     ": the bag holds no messages (a valid bag, but nothing was recorded in "
                     "it: was the recorder started before the sensors published?)");
    for (const auto* t : {&imu_state.summary, &lidar_state.summary})
      if (t->in_bag == 0)
        throw BagError(path + ": no message on topic " + t->topic + " (set " +
                       (t == &imu_state.summary ? "imu_topic" : "lidar_topic") +
                       "); the bag has:" + all_topics());
    if (by_trigger && summary.trigger.in_bag == 0)
      throw BagError(path + ": no message on topic " + config.trigger_topic +
                     " (set trigger_topic, or another stamp_source); the bag has:" + all_topics());
  }

  std::vector<std::uint8_t> buf;  // one serialized message

  // The triggers, by seq (a few bytes per scan).
  struct Trigger {
    double stamp, bag_time;
    bool used = false;
  };
  std::multimap<std::uint32_t, Trigger> triggers;
  if (by_trigger) {
    std::size_t k = 0;
    try {
      for (const rosbag::MessageInstance& m :
           rosbag::View(bag, rosbag::TopicQuery(config.trigger_topic))) {
        const std::string where =
            path + ": " + config.trigger_topic + " message " + std::to_string(k++);
        std_msgs::Header h;
        try {
          readMessage(m, RosMessage::kHeader, buf, h);
        } catch (const std::exception& e) {
          throw BagError(where + ": " + e.what());
        }
        triggers.emplace(h.seq, Trigger{h.stamp.toSec(), m.getTime().toSec()});
      }
    } catch (const BagError&) {
      throw;
    } catch (const std::exception& e) {
      throw BagError(path + ": " + config.trigger_topic + " after " + std::to_string(k) +
                     " messages: " + e.what() + " (truncated or corrupted bag?)");
    }
    for (auto it = triggers.begin(); it != triggers.end(); ++it)
      if (triggers.count(it->first) > 1) ++summary.trigger.repeated_seq;
  }
  std::vector<double> bag_delays;

  // The reorder buffer and the stream-wide order check.
  std::map<PendingKey, Pending> buffer;
  std::size_t arrival = 0;
  double written_up_to = -1, newest = -1;
  auto emit = [&](std::map<PendingKey, Pending>::iterator it) {
    const auto& [t, kind, seq] = it->first;
    written_up_to = t;
    if (kind == 0) {
      cb.imu(it->second.imu);
    } else {
      cb.frame(std::move(it->second.frame));
    }
    buffer.erase(it);
  };
  auto push = [&](double t, int kind, Pending&& p, const std::string& where) {
    if (t < written_up_to)
      throw BagError(where + ": stamped " + fmt(t) + ", but messages up to " + fmt(written_up_to) +
                     " were already written: it arrived more than reorder_window = " +
                     fmt(config.reorder_window, 3) + " s late; increase reorder_window");
    buffer.emplace(PendingKey{t, kind, arrival++}, std::move(p));
    newest = std::max(newest, t);
    while (!buffer.empty() && std::get<0>(buffer.begin()->first) < newest - config.reorder_window)
      emit(buffer.begin());
  };

  const double accel_scale = config.imu_accel_in_g ? kGravity : 1.0;
  Vec3 accel_sum = Vec3::Zero();
  int accel_n = 0;
  auto checkUnit = [&](const std::string& where) {
    summary.accel_mean_norm = (accel_sum / accel_n).norm();
    const double g = summary.accel_mean_norm;
    const AccelUnitMismatch unit = accelUnitMismatch(g, config.imu_accel_in_g);
    if (unit == AccelUnitMismatch::kDataInG)
      throw BagError(where + ": the mean specific force of the first " + std::to_string(accel_n) +
                     " IMU samples is " + fmt(g, 3) +
                     ": the IMU reports g, not m/s^2 (set imu_accel_unit = g)");
    if (unit == AccelUnitMismatch::kDataInMs2)
      throw BagError(where + ": imu_accel_unit = g, but the first " + std::to_string(accel_n) +
                     " IMU samples average " + fmt(g, 2) +
                     " m/s^2 after conversion: the IMU reports m/s^2");
  };

  auto imuMessage = [&](const rosbag::MessageInstance& m, const std::string& where) {
    sensor_msgs::Imu msg;
    readMessage(m, RosMessage::kImu, buf, msg);
    if (msg.angular_velocity_covariance[0] == -1 || msg.linear_acceleration_covariance[0] == -1)
      throw BagError(
          where + ": the IMU declares no " +
          (msg.angular_velocity_covariance[0] == -1 ? "angular velocity" : "linear acceleration") +
          " (covariance[0] = -1)");
    Pending p;
    p.imu.t = msg.header.stamp.toSec();
    p.imu.gyro = Vec3(msg.angular_velocity.x, msg.angular_velocity.y, msg.angular_velocity.z);
    p.imu.accel = accel_scale * Vec3(msg.linear_acceleration.x, msg.linear_acceleration.y,
                                     msg.linear_acceleration.z);
    if (!p.imu.gyro.allFinite() || !p.imu.accel.allFinite()) {
      ++imu_state.summary.unusable;
    } else if (imu_state.accept(p.imu.t)) {
      if (accel_n < config.unit_check_samples) {
        accel_sum += p.imu.accel;
        if (++accel_n == config.unit_check_samples) checkUnit(where);
      }
      imu_state.stamps.push_back(p.imu.t);
      push(p.imu.t, 0, std::move(p), where);
    }
  };

  DecodeStats decode_stats;
  auto cloudMessage = [&](const rosbag::MessageInstance& m, const std::string& where) {
    sensor_msgs::PointCloud2 msg;
    readMessage(m, RosMessage::kPointCloud2, buf, msg);
    Pending p;
    try {
      p.frame = decodeCloud(msg, config.cloud, config.drop_invalid_points, &decode_stats);
    } catch (const LayoutError& e) {
      throw BagError(where + ": " + e.what());
    }
    // The scan stamp the point offsets are relative to.
    double stamp = 0;
    switch (config.stamp_source) {
      case StampSource::kHeader:
        stamp = msg.header.stamp.isZero() ? 0.0 : msg.header.stamp.toSec();
        break;
      case StampSource::kBagTime:
        stamp = m.getTime().toSec();
        break;
      case StampSource::kTrigger: {
        const auto [first, last] = triggers.equal_range(msg.header.seq);
        if (first == last) {
          ++lidar_state.summary.untriggered;
          return;
        }
        const double bag_time = m.getTime().toSec();
        auto best = first;
        for (auto it = first; it != last; ++it)
          if (std::abs(it->second.bag_time - bag_time) < std::abs(best->second.bag_time - bag_time))
            best = it;
        if (!best->second.used) ++summary.trigger.used;
        best->second.used = true;
        stamp = best->second.stamp;
        bag_delays.push_back(bag_time - stamp);
        break;
      }
    }
    p.frame.stamp = stamp + config.lidar_time_offset;
    if (p.frame.points.empty() || stamp == 0) {
      ++lidar_state.summary.unusable;
    } else if (lidar_state.accept(p.frame.stamp)) {
      summary.points += p.frame.points.size();
      lidar_state.stamps.push_back(p.frame.stamp);
      const double t = p.frame.stamp;
      push(t, 1, std::move(p), where);
    }
  };

  std::size_t done = 0, imu_index = 0, lidar_index = 0, total = 0;
  try {
    rosbag::View view(
        bag, rosbag::TopicQuery(std::vector<std::string>{config.imu_topic, config.lidar_topic}));
    total = view.size();
    for (const rosbag::MessageInstance& m : view) {
      const bool is_imu = m.getTopic() == config.imu_topic;
      const std::string where = path + ": " + (is_imu ? config.imu_topic : config.lidar_topic) +
                                " message " + std::to_string(is_imu ? imu_index++ : lidar_index++);
      try {
        if (is_imu)
          imuMessage(m, where);
        else
          cloudMessage(m, where);
      } catch (const BagError&) {
        throw;
      } catch (const std::exception& e) {  // bad_alloc included: one line naming the message
        throw BagError(where + ": " + e.what());
      }
      if (cb.progress) cb.progress(++done, total);
    }
  } catch (const BagError&) {
    throw;
  } catch (const std::exception& e) {  // format errors of the bag, overruns of a message
    throw BagError(path + ": after " + std::to_string(done) + " of " + std::to_string(total) +
                   " messages: " + e.what() + " (truncated or corrupted bag?)");
  }
  if (accel_n > 0 && accel_n < config.unit_check_samples) checkUnit(path + ": " + config.imu_topic);
  while (!buffer.empty()) emit(buffer.begin());

  summary.invalid_points = decode_stats.invalid_points;
  summary.trigger.median_bag_delay = median(bag_delays);
  imu_state.finish(config.gap_factor);
  lidar_state.finish(config.gap_factor);
  summary.imu = imu_state.summary;
  summary.lidar = lidar_state.summary;
  for (const auto* t : {&summary.imu, &summary.lidar})
    if (t->imported == 0)
      throw BagError(path + ": no usable message on " + t->topic + " (" +
                     std::to_string(t->skipped()) + " skipped)");
  return summary;
}

}  // namespace freeinit::ros1
