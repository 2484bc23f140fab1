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
#include <memory>

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
  // The smallest TransformStamped, empty strings: seq, stamp, two string lengths, 7 doubles.
  in.need(std::size_t{count} * 76);
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

ros::Time rosTime(std::int64_t ns) {
  if (ns <= 1) return ros::TIME_MIN;
  if (ns >= std::int64_t{std::numeric_limits<std::uint32_t>::max()} * 1000000000)
    return ros::TIME_MAX;
  ros::Time t;
  t.fromNSec(static_cast<std::uint64_t>(ns));
  return t;
}

/// [s] bag time: a trigger is read up to this far ahead of (and from this far before the start
/// of) the clouds it may stamp; the nearest of the triggers with a cloud's seq is chosen.
constexpr double kTriggerSlack = 2.0;

// The chunks that hold a topic's messages, by the bag time of their first message, to find those
// holding a message of a given time (all chunks a message at `t` may be in: first <= t <= last).
struct TopicChunks {
  std::vector<std::uint64_t> first, last, last_so_far;  // [ns]; last_so_far: max of last[0..i]
  std::vector<std::size_t> chunk;
};

TopicChunks topicChunks(const BagIndex& index, const std::string& topic) {
  std::vector<std::tuple<std::uint64_t, std::uint64_t, std::size_t>> v;
  for (std::size_t k = 0; k < index.chunks.size(); ++k)
    for (const auto& [conn, span] : index.chunks[k].connections) {
      const auto t = index.topics.find(conn);
      if (t != index.topics.end() && t->second == topic && span.messages > 0)
        v.emplace_back(span.first, span.last, k);
    }
  std::sort(v.begin(), v.end());
  TopicChunks c;
  for (const auto& [first, last, k] : v) {
    c.first.push_back(first);
    c.last.push_back(last);
    c.last_so_far.push_back(c.last_so_far.empty() ? last : std::max(last, c.last_so_far.back()));
    c.chunk.push_back(k);
  }
  return c;
}

// The LiDAR pose in the IMU frame from config.tf_static_topic of an open bag (see
// readStaticExtrinsics); `bytes(m, buf)` puts the serialized message `m` in `buf`.
template <class Bytes>
std::optional<bags::RecordedExtrinsics> extrinsicsOf(rosbag::Bag& bag, const std::string& path,
                                                     const BagImportConfig& config,
                                                     std::vector<std::uint8_t>& buf,
                                                     const Bytes& bytes) {
  std::vector<ros2::TransformStamped> transforms;
  std::string imu_frame, lidar_frame;
  try {
    rosbag::View tf(bag, rosbag::TopicQuery(config.tf_static_topic));
    if (tf.size() == 0) return std::nullopt;
    for (const rosbag::ConnectionInfo* c : tf.getConnections())
      if (c->datatype != "tf2_msgs/TFMessage" && c->datatype != "tf/tfMessage")
        throw BagError(path + ": topic " + c->topic + " has type " + c->datatype +
                       ", expected tf2_msgs/TFMessage (tf_static_topic)");
    std::size_t k = 0;
    for (const rosbag::MessageInstance& m : tf) {
      bytes(m, buf);
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
        bytes(m, buf);
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

void serialized(const rosbag::MessageInstance& m, std::vector<std::uint8_t>& buf) {
  buf.resize(m.size());
  ros::serialization::OStream out(buf.data(), static_cast<std::uint32_t>(buf.size()));
  m.write(out);
}

}  // namespace

struct Ros1Reader::Impl {
  std::string path;
  BagImportConfig config;
  bool whole_file_checked = false;
  std::unique_ptr<CheckedBag> checked;
  rosbag::Bag bag;
  mutable BagSummary summary;
  std::uint64_t first_ns = 0, last_ns = 0;  // [ns] the bag's time span (index)
  std::map<std::string, TopicChunks> chunks_of;

  // The window.
  std::unique_ptr<rosbag::View> view;
  rosbag::View::iterator it;
  std::size_t done = 0, total = 0;
  std::size_t imu_index = 0, lidar_index = 0;
  double last_log_time = 0;       // [s] UNIX
  std::uint64_t last_log_ns = 0;  // [ns] UNIX, the same

  // The triggers (stamp_source = trigger), by seq, read up to trigger_read_to.
  struct Trigger {
    double stamp, bag_time;
    bool used = false;
  };
  std::multimap<std::uint32_t, Trigger> triggers;
  std::unique_ptr<rosbag::View> trigger_view;
  rosbag::View::iterator trigger_it;
  std::size_t trigger_index = 0;
  std::vector<double> bag_delays;

  DecodeStats decode_stats;
  std::vector<ros2::PointField> fields;
  std::vector<std::uint8_t> buf;  // one serialized message

  /// Checks the chunks that may hold the message of `topic` recorded at `t`, before librosbag
  /// reads them.
  void ensureChecked(const std::string& topic, const ros::Time& t) {
    if (whole_file_checked) return;
    auto c = chunks_of.find(topic);
    if (c == chunks_of.end())
      c = chunks_of.emplace(topic, topicChunks(checked->index(), topic)).first;
    const TopicChunks& tc = c->second;
    const std::uint64_t ns = t.toNSec();
    auto i = static_cast<std::size_t>(std::upper_bound(tc.first.begin(), tc.first.end(), ns) -
                                      tc.first.begin());
    while (i > 0) {
      --i;
      if (tc.last_so_far[i] < ns) break;
      if (tc.last[i] >= ns) checked->checkChunk(tc.chunk[i]);
    }
  }

  template <class T>
  void read(const rosbag::MessageInstance& m, RosMessage type, T& msg) {
    ensureChecked(m.getTopic(), m.getTime());
    readMessage(m, type, buf, msg);
  }

  /// Reads the triggers recorded up to bag time `until` [s].
  void readTriggers(double until) {
    if (!trigger_view) return;
    try {
      for (; trigger_it != trigger_view->end(); ++trigger_it) {
        const rosbag::MessageInstance& m = *trigger_it;
        const double bag_time = m.getTime().toSec();
        if (bag_time > until) return;
        const std::string where =
            path + ": " + config.trigger_topic + " message " + std::to_string(trigger_index++);
        std_msgs::Header h;
        try {
          read(m, RosMessage::kHeader, h);
        } catch (const BagError&) {
          throw;
        } catch (const std::exception& e) {
          throw BagError(where + ": " + e.what());
        }
        const auto n = triggers.count(h.seq);
        summary.trigger.repeated_seq += n == 0 ? 0 : n == 1 ? 2 : 1;
        triggers.emplace(h.seq, Trigger{h.stamp.toSec(), bag_time});
      }
    } catch (const BagError&) {
      throw;
    } catch (const std::exception& e) {
      throw BagError(path + ": " + config.trigger_topic + " after " +
                     std::to_string(trigger_index) + " messages: " + e.what() +
                     " (truncated or corrupted bag?)");
    }
  }

  void imuMessage(const rosbag::MessageInstance& m, const std::string& where,
                  bags::ImportStream& stream) {
    sensor_msgs::Imu msg;
    read(m, RosMessage::kImu, msg);
    stream.imu(bags::imuSampleOf(msg, msg.header.stamp.toSec(), where), where);
  }

  void cloudMessage(const rosbag::MessageInstance& m, const std::string& where,
                    bags::ImportStream& stream) {
    sensor_msgs::PointCloud2 msg;
    read(m, RosMessage::kPointCloud2, msg);
    LidarFrame frame;
    try {
      frame = bags::decodeCloud(ros1::view(msg, fields), config.cloud, config.drop_invalid_points,
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
        const double bag_time = m.getTime().toSec();
        readTriggers(bag_time + kTriggerSlack);
        const auto [first, last] = triggers.equal_range(msg.header.seq);
        if (first == last) {
          stream.untriggered();
          return;
        }
        auto best = first;
        for (auto i = first; i != last; ++i)
          if (std::abs(i->second.bag_time - bag_time) < std::abs(best->second.bag_time - bag_time))
            best = i;
        if (!best->second.used) ++summary.trigger.used;
        best->second.used = true;
        stamp = best->second.stamp;
        bag_delays.push_back(bag_time - stamp);
        break;
      }
    }
    stream.frame(std::move(frame), stamp, where);
  }
};

Ros1Reader::Ros1Reader(const std::string& path, const BagImportConfig& config, Check check)
    : impl_(std::make_unique<Impl>()) {
  Impl& x = *impl_;
  x.path = path;
  x.config = config;
  validate(config);
  // The structure first: librosbag trusts every length in the file.
  if (check == Check::kWholeFile) {
    checkBagFile(path);
    x.whole_file_checked = true;
  }
  x.checked = std::make_unique<CheckedBag>(path);
  for (const auto& c : x.checked->index().chunks)
    for (const auto& [conn, span] : c.connections) {
      if (span.messages == 0) continue;
      x.first_ns = x.first_ns == 0 ? span.first : std::min(x.first_ns, span.first);
      x.last_ns = std::max(x.last_ns, span.last);
    }
  rosbag::Bag& bag = x.bag;
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
  BagSummary& summary = x.summary;
  summary.file = path;
  summary.kind = "a ROS 1 bag";
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
  summary.imu = imu_summary;
  summary.lidar = lidar_summary;
}

Ros1Reader::~Ros1Reader() = default;

const std::string& Ros1Reader::path() const { return impl_->path; }

std::optional<bags::RecordedExtrinsics> Ros1Reader::staticExtrinsics() {
  Impl& x = *impl_;
  if (x.config.tf_static_topic.empty()) return std::nullopt;
  return extrinsicsOf(x.bag, x.path, x.config, x.buf,
                      [&](const rosbag::MessageInstance& m, std::vector<std::uint8_t>& buf) {
                        x.ensureChecked(m.getTopic(), m.getTime());
                        serialized(m, buf);
                      });
}

const BagSummary& Ros1Reader::summary() const {
  impl_->summary.trigger.median_bag_delay = median(impl_->bag_delays);
  return impl_->summary;
}

std::pair<std::size_t, std::size_t> Ros1Reader::messages() const {
  return {impl_->done, impl_->total};
}

std::size_t Ros1Reader::invalidPoints() const { return impl_->decode_stats.invalid_points; }

const CheckedBag& Ros1Reader::checked() const { return *impl_->checked; }

double Ros1Reader::lastLogTime() const { return impl_->last_log_time; }

std::pair<std::int64_t, std::int64_t> Ros1Reader::progress() const {
  const Impl& x = *impl_;
  if (x.last_ns <= x.first_ns) return {0, 0};
  const auto span = static_cast<std::int64_t>(x.last_ns - x.first_ns);
  if (x.done == 0) return {0, span};
  const std::int64_t past =
      static_cast<std::int64_t>(x.last_log_ns) - static_cast<std::int64_t>(x.first_ns);
  return {std::clamp<std::int64_t>(past, 0, span), span};
}

void Ros1Reader::start(std::int64_t from, std::int64_t to) {
  Impl& x = *impl_;
  const BagImportConfig& config = x.config;
  x.done = 0;
  x.trigger_view.reset();
  try {
    // Messages are named by their number in the topic: those before the window are counted from
    // the index.
    auto before = [&](const std::string& topic, std::int64_t t) -> std::size_t {
      if (rosTime(t) <= ros::TIME_MIN) return 0;
      return rosbag::View(x.bag, rosbag::TopicQuery(topic), ros::TIME_MIN, rosTime(t - 1)).size();
    };
    x.imu_index = before(config.imu_topic, from);
    x.lidar_index = before(config.lidar_topic, from);
    x.view = std::make_unique<rosbag::View>(
        x.bag, rosbag::TopicQuery(std::vector<std::string>{config.imu_topic, config.lidar_topic}),
        rosTime(from), rosTime(to));
    x.total = x.view->size();
    x.it = x.view->begin();
    if (config.stamp_source == StampSource::kTrigger) {
      // From kTriggerSlack before the window: a cloud's trigger is recorded before it.
      const std::int64_t lead = static_cast<std::int64_t>(kTriggerSlack * 1e9);
      const std::int64_t trigger_from =
          from < std::numeric_limits<std::int64_t>::min() + lead ? from : from - lead;
      x.triggers.clear();
      x.trigger_view = std::make_unique<rosbag::View>(
          x.bag, rosbag::TopicQuery(config.trigger_topic), rosTime(trigger_from), rosTime(to));
      x.trigger_it = x.trigger_view->begin();
      x.trigger_index = before(config.trigger_topic, trigger_from);
    }
  } catch (const std::exception& e) {
    throw BagError(x.path + ": cannot read the bag's index: " + e.what() + " (corrupt bag?)");
  }
  // The importer's order: every trigger first.
  if (x.whole_file_checked) x.readTriggers(std::numeric_limits<double>::infinity());
}

bool Ros1Reader::step(bags::ImportStream& stream) {
  Impl& x = *impl_;
  const BagImportConfig& config = x.config;
  if (!x.view) start();
  try {
    if (x.it == x.view->end()) return false;
    const rosbag::MessageInstance& m = *x.it;
    const bool is_imu = m.getTopic() == config.imu_topic;
    const std::string where = x.path + ": " + (is_imu ? config.imu_topic : config.lidar_topic) +
                              " message " +
                              std::to_string(is_imu ? x.imu_index++ : x.lidar_index++);
    x.last_log_time = m.getTime().toSec();
    x.last_log_ns = m.getTime().toNSec();
    try {
      if (is_imu)
        x.imuMessage(m, where, stream);
      else
        x.cloudMessage(m, where, stream);
    } catch (const BagError&) {
      throw;
    } catch (const std::exception& e) {  // bad_alloc included: one line naming the message
      throw BagError(where + ": " + e.what());
    }
    ++x.done;
    ++x.it;
  } catch (const BagError&) {
    throw;
  } catch (const std::exception& e) {  // format errors of the bag, overruns of a message
    throw BagError(x.path + ": after " + std::to_string(x.done) + " of " + std::to_string(x.total) +
                   " messages: " + e.what() + " (truncated or corrupted bag?)");
  }
  return true;
}

BagSummary readBag(const std::string& path, const BagImportConfig& config,
                   const BagReadCallbacks& cb) {
  Ros1Reader reader(path, config, Ros1Reader::Check::kWholeFile);
  bags::ImportStream stream(config, cb);
  reader.start();
  while (reader.step(stream))
    if (cb.progress) {
      const auto [done, total] = reader.messages();
      cb.progress(done, total);
    }
  stream.finish(path + ": " + config.imu_topic);
  BagSummary summary = reader.summary();
  summary.kind.clear();  // the importer's summary starts "Bag <file>:", as it always has
  stream.summarize(summary, reader.invalidPoints());
  return summary;
}

std::optional<bags::RecordedExtrinsics> readStaticExtrinsics(const std::string& path,
                                                             const BagImportConfig& config) {
  if (config.tf_static_topic.empty()) return std::nullopt;
  checkBagFile(path);
  rosbag::Bag bag;
  try {
    bag.open(path, rosbag::bagmode::Read);
  } catch (const std::exception& e) {
    throw BagError(path + ": " + config.tf_static_topic + ": " + e.what());
  }
  std::vector<std::uint8_t> buf;
  return extrinsicsOf(bag, path, config, buf, serialized);
}

}  // namespace freeinit::ros1
