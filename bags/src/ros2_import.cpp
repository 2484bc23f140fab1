#include <freeinit/bags/ros2_import.h>
#include <freeinit/ros2/message_decoding.h>
#include <freeinit/ros2/open_recording.h>

#include <algorithm>
#include <exception>

namespace freeinit::bags {
namespace {

std::string countOf(const ros2::TopicInfo& t) {
  return t.message_count ? ", " + std::to_string(*t.message_count) + " messages" : "";
}

}  // namespace

double rosSeconds(std::int64_t ns) {
  std::int64_t sec = ns / 1000000000, nsec = ns % 1000000000;
  if (nsec < 0) {
    nsec += 1000000000;
    --sec;
  }
  return static_cast<double>(sec) + 1e-9 * static_cast<double>(nsec);
}

Ros2Reader::Ros2Reader(const std::string& path, const BagImportConfig& config) : config_(config) {
  validate(config_);
  try {
    rec_ = ros2::openRecording(path);
  } catch (const ros2::RecordingError& e) {
    throw BagError(e.what());
  }
  const std::string where = path + ": " + rec_->kind();
  if (config_.stamp_source == StampSource::kTrigger)
    throw BagError(where + ": stamp_source = trigger matches clouds to triggers by header.seq, " +
                   "which ROS 2 headers do not have (use header or bag_time)");
  auto find = [&](const std::string& name, const char* type, const char* key) {
    const auto& topics = rec_->topics();
    if (std::none_of(topics.begin(), topics.end(),
                     [&](const ros2::TopicInfo& t) { return t.name == name; }))
      throw BagError(where + ": no topic " + name + " (set " + key +
                     "); the recording has: " + rec_->topicList());
    try {
      return rec_->topic(name, type);
    } catch (const ros2::RecordingError& e) {
      throw BagError(std::string(e.what()) + " (" + key + ")");
    }
  };
  imu_topic_ = find(config_.imu_topic, ros2::kImuType, "imu_topic");
  lidar_topic_ = find(config_.lidar_topic, ros2::kPointCloud2Type, "lidar_topic");
  summary_.file = path;
  summary_.kind = rec_->kind();
  summary_.warnings = rec_->warnings();
  for (std::size_t i = 0; i < rec_->topics().size(); ++i) {
    const ros2::TopicInfo& t = rec_->topics()[i];
    TopicSummary* s = i == imu_topic_     ? &summary_.imu
                      : i == lidar_topic_ ? &summary_.lidar
                                          : nullptr;
    if (s == nullptr) {
      summary_.other_topics.push_back(t.name + " (" + (t.type.empty() ? "no type" : t.type) +
                                      countOf(t) + ")");
      continue;
    }
    s->topic = t.name;
    s->type = t.type;
    s->in_bag = t.message_count ? static_cast<std::size_t>(*t.message_count) : 0;
  }
}

Ros2Reader::~Ros2Reader() = default;

const std::string& Ros2Reader::path() const { return rec_->path(); }

std::string Ros2Reader::firstFrameId(std::size_t topic, bool imu) {
  rec_->start({std::numeric_limits<std::int64_t>::min(),
               std::numeric_limits<std::int64_t>::max(),
               {topic}});
  ros2::Message m;
  if (!rec_->next(m)) return "";
  try {
    return imu ? ros2::decodeImu(m.data).header.frame_id
               : ros2::decodePointCloud2(m.data).header.frame_id;
  } catch (const std::exception& e) {
    throw BagError(rec_->path() + ": " + rec_->topics()[topic].name + " message 0: " + e.what());
  }
}

std::optional<RecordedExtrinsics> Ros2Reader::staticExtrinsics() {
  if (config_.tf_static_topic.empty()) return std::nullopt;
  const auto& topics = rec_->topics();
  const auto it = std::find_if(topics.begin(), topics.end(), [&](const ros2::TopicInfo& t) {
    return t.name == config_.tf_static_topic;
  });
  if (it == topics.end()) return std::nullopt;
  std::size_t tf = 0;
  try {
    tf = rec_->topic(config_.tf_static_topic, ros2::kTFMessageType);
  } catch (const ros2::RecordingError& e) {
    throw BagError(std::string(e.what()) + " (tf_static_topic)");
  }
  std::vector<ros2::TransformStamped> transforms;
  rec_->start(
      {std::numeric_limits<std::int64_t>::min(), std::numeric_limits<std::int64_t>::max(), {tf}});
  ros2::Message m;
  for (std::size_t n = 0; rec_->next(m); ++n) {
    try {
      for (auto& t : ros2::decodeTFMessage(m.data).transforms) transforms.push_back(std::move(t));
    } catch (const std::exception& e) {
      throw BagError(rec_->path() + ": " + config_.tf_static_topic + " message " +
                     std::to_string(n) + ": " + e.what());
    }
  }
  const std::string imu_frame = firstFrameId(imu_topic_, true);
  const std::string lidar_frame = firstFrameId(lidar_topic_, false);
  return extrinsicsFromTransforms(transforms, imu_frame, lidar_frame);
}

void Ros2Reader::start(std::int64_t from, std::int64_t to) {
  rec_->start({from, to, {imu_topic_, lidar_topic_}});
}

bool Ros2Reader::step(ImportStream& stream) {
  if (!rec_->next(msg_)) return false;
  last_log_time_ = msg_.log_time;
  const bool is_imu = msg_.topic == imu_topic_;
  const std::string where = rec_->path() + ": " +
                            (is_imu ? config_.imu_topic : config_.lidar_topic) + " message " +
                            std::to_string(is_imu ? imu_read_++ : clouds_read_++);
  try {
    if (is_imu) {
      const ros2::Imu m = ros2::decodeImu(msg_.data);
      stream.imu(imuSampleOf(m, m.header.stamp.seconds(), where), where);
    } else {
      const ros2::PointCloud2 m = ros2::decodePointCloud2(msg_.data);
      const PointCloudView v = view(m);
      LidarFrame frame;
      try {
        frame = decodeCloud(v, config_.cloud, config_.drop_invalid_points, &stats_);
      } catch (const LayoutError& e) {
        throw BagError(where + ": " + e.what());
      }
      const double stamp = config_.stamp_source == StampSource::kBagTime ? rosSeconds(msg_.log_time)
                           : v.stampIsZero()                             ? 0.0
                                                                         : v.stamp();
      stream.frame(std::move(frame), stamp, where);
    }
  } catch (const BagError&) {
    throw;
  } catch (const std::exception& e) {  // CDR errors, bad_alloc: one line naming the message
    throw BagError(where + ": " + e.what());
  }
  return true;
}

std::pair<std::int64_t, std::int64_t> Ros2Reader::progress() const {
  const auto& range = rec_->timeRange();
  if (!range || range->last <= range->first) return {0, 0};
  const std::int64_t span = range->last - range->first;
  return {std::clamp<std::int64_t>(last_log_time_ - range->first, 0, span), span};
}

BagSummary readRos2Recording(const std::string& path, const BagImportConfig& config,
                             const BagReadCallbacks& callbacks) {
  Ros2Reader reader(path, config);
  ImportStream stream(config, callbacks);
  reader.start();
  try {
    while (reader.step(stream))
      if (callbacks.progress) {
        // In thousandths of the log-time span (the messages are not counted ahead).
        const auto [done, total] = reader.progress();
        if (total > 0)
          callbacks.progress(static_cast<std::size_t>(static_cast<double>(done) /
                                                      static_cast<double>(total) * 1000),
                             1000);
      }
  } catch (const BagError&) {
    throw;
  } catch (const std::exception& e) {  // the container: a corrupt chunk, a cut .db3
    throw BagError(e.what());
  }
  stream.finish(path + ": " + config.imu_topic);
  BagSummary summary = reader.summary();
  // Without counts in the recording (a single .db3), what was read.
  if (summary.imu.in_bag == 0) summary.imu.in_bag = reader.imuRead();
  if (summary.lidar.in_bag == 0) summary.lidar.in_bag = reader.cloudsRead();
  stream.summarize(summary, reader.invalidPoints());
  return summary;
}

}  // namespace freeinit::bags
