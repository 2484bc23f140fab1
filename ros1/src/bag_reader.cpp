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
#include <cstring>
#include <map>

namespace freeinit::ros1 {
namespace {

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

// A serialized tf2_msgs/TFMessage (ROS 1), every length checked against the bytes left.
class Ros1Bytes {
 public:
  Ros1Bytes(const std::uint8_t* p, std::size_t n) : p_(p), n_(n) {}
  template <class T>
  T get() {
    need(sizeof(T));
    T v;
    std::memcpy(&v, p_ + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  std::string text() {
    const auto len = get<std::uint32_t>();
    need(len);
    std::string s(reinterpret_cast<const char*>(p_ + pos_), len);
    pos_ += len;
    return s;
  }
  void need(std::size_t k) const {
    if (k > n_ - pos_)
      throw std::runtime_error("a length of " + std::to_string(k) + " bytes at byte " +
                               std::to_string(pos_) + " of a " + std::to_string(n_) +
                               "-byte message");
  }

 private:
  const std::uint8_t* p_;
  std::size_t n_, pos_ = 0;
};

std::vector<ros2::TransformStamped> parseTfMessage(const std::uint8_t* data, std::size_t n) {
  Ros1Bytes in(data, n);
  const auto count = in.get<std::uint32_t>();
  in.need(std::size_t{count} * 92);  // the smallest TransformStamped: empty strings
  std::vector<ros2::TransformStamped> out(count);
  for (auto& t : out) {
    in.get<std::uint32_t>();  // seq
    t.header.stamp.sec = static_cast<std::int32_t>(in.get<std::uint32_t>());
    t.header.stamp.nanosec = in.get<std::uint32_t>();
    t.header.frame_id = in.text();
    t.child_frame_id = in.text();
    t.translation = {in.get<double>(), in.get<double>(), in.get<double>()};
    t.rotation.x = in.get<double>();
    t.rotation.y = in.get<double>();
    t.rotation.z = in.get<double>();
    t.rotation.w = in.get<double>();
  }
  return out;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

}  // namespace

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
  TopicSummary imu_summary, lidar_summary;  // topic, type and messages in the bag
  imu_summary.topic = config.imu_topic;
  lidar_summary.topic = config.lidar_topic;
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
        imu_summary.type = type;
        imu_summary.in_bag = n;
      } else if (topic == config.lidar_topic) {
        lidar_summary.type = type;
        lidar_summary.in_bag = n;
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
    for (const auto* t : {&imu_summary, &lidar_summary})
      if (t->in_bag == 0)
        throw BagError(path + ": no message on topic " + t->topic + " (set " +
                       (t == &imu_summary ? "imu_topic" : "lidar_topic") +
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

  bags::ImportStream stream(config, cb);
  auto imuMessage = [&](const rosbag::MessageInstance& m, const std::string& where) {
    sensor_msgs::Imu msg;
    readMessage(m, RosMessage::kImu, buf, msg);
    if (msg.angular_velocity_covariance[0] == -1 || msg.linear_acceleration_covariance[0] == -1)
      throw BagError(
          where + ": the IMU declares no " +
          (msg.angular_velocity_covariance[0] == -1 ? "angular velocity" : "linear acceleration") +
          " (covariance[0] = -1)");
    ImuSample s;
    s.t = msg.header.stamp.toSec();
    s.gyro = Vec3(msg.angular_velocity.x, msg.angular_velocity.y, msg.angular_velocity.z);
    s.accel = Vec3(msg.linear_acceleration.x, msg.linear_acceleration.y, msg.linear_acceleration.z);
    stream.imu(s, where);
  };

  DecodeStats decode_stats;
  std::vector<ros2::PointField> fields;
  auto cloudMessage = [&](const rosbag::MessageInstance& m, const std::string& where) {
    sensor_msgs::PointCloud2 msg;
    readMessage(m, RosMessage::kPointCloud2, buf, msg);
    LidarFrame frame;
    try {
      frame = bags::decodeCloud(view(msg, fields), config.cloud, config.drop_invalid_points,
                                &decode_stats);
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
          stream.untriggered();
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
    stream.frame(std::move(frame), stamp, where);
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
  stream.finish(path + ": " + config.imu_topic);
  summary.trigger.median_bag_delay = median(bag_delays);
  summary.imu = imu_summary;
  summary.lidar = lidar_summary;
  stream.summarize(summary, decode_stats.invalid_points);
  return summary;
}

}  // namespace freeinit::ros1

namespace freeinit::ros1 {

std::optional<bags::RecordedExtrinsics> readStaticExtrinsics(const std::string& path,
                                                             const BagImportConfig& config) {
  if (config.tf_static_topic.empty()) return std::nullopt;
  checkBagFile(path);
  rosbag::Bag bag;
  std::vector<std::uint8_t> buf;
  std::vector<ros2::TransformStamped> transforms;
  std::string imu_frame, lidar_frame;
  try {
    bag.open(path, rosbag::bagmode::Read);
    rosbag::View tf(bag, rosbag::TopicQuery(config.tf_static_topic));
    if (tf.size() == 0) return std::nullopt;
    for (const rosbag::ConnectionInfo* c : tf.getConnections())
      if (c->datatype != "tf2_msgs/TFMessage" && c->datatype != "tf/tfMessage")
        throw BagError(path + ": topic " + c->topic + " has type " + c->datatype +
                       ", expected tf2_msgs/TFMessage (tf_static_topic)");
    std::size_t k = 0;
    for (const rosbag::MessageInstance& m : tf) {
      buf.resize(m.size());
      ros::serialization::OStream out(buf.data(), static_cast<std::uint32_t>(buf.size()));
      m.write(out);
      try {
        for (auto& t : parseTfMessage(buf.data(), buf.size())) transforms.push_back(std::move(t));
      } catch (const std::exception& e) {
        throw BagError(path + ": " + config.tf_static_topic + " message " + std::to_string(k) +
                       ": " + e.what());
      }
      ++k;
    }
    // The frame_id of the first message of a topic: both types start with a std_msgs/Header.
    auto frameOf = [&](const std::string& topic) -> std::string {
      rosbag::View v(bag, rosbag::TopicQuery(topic));
      for (const rosbag::MessageInstance& m : v) {
        buf.resize(m.size());
        ros::serialization::OStream out(buf.data(), static_cast<std::uint32_t>(buf.size()));
        m.write(out);
        checkSerialized(RosMessage::kHeader, buf.data(), buf.size(), false);
        std_msgs::Header h;
        ros::serialization::IStream in(buf.data(), static_cast<std::uint32_t>(buf.size()));
        ros::serialization::deserialize(in, h);
        return h.frame_id;
      }
      return "";
    };
    imu_frame = frameOf(config.imu_topic);
    lidar_frame = frameOf(config.lidar_topic);
  } catch (const BagError&) {
    throw;
  } catch (const std::exception& e) {
    throw BagError(path + ": " + config.tf_static_topic + ": " + e.what());
  }
  return bags::extrinsicsFromTransforms(transforms, imu_frame, lidar_frame);
}

}  // namespace freeinit::ros1
