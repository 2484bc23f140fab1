#include <freeinit/app_support/recording_source.h>
#include <freeinit/bags/ros2_import.h>
#include <freeinit/mrpt_plugins/conversions.h>
#include <freeinit/ros2/open_recording.h>
#ifdef FREEINIT_WITH_ROSBAG
#include <freeinit/ros1/bag_reader.h>
#endif

#include <algorithm>
#include <cmath>
#include <deque>
#include <filesystem>
#include <limits>

namespace freeinit::app_support {
namespace {

using mrpt_plugins::InputError;
using mrpt_plugins::RawlogObject;

// [ns] of a UNIX time in s, saturating.
std::int64_t toNs(double t) {
  if (!(t > -9.2e9)) return std::numeric_limits<std::int64_t>::min();
  if (!(t < 9.2e9)) return std::numeric_limits<std::int64_t>::max();
  return static_cast<std::int64_t>(std::floor(t * 1e9));
}

// A recording of either ROS generation as a source of rawlog records.
class BagSource : public mrpt_plugins::RecordSource {
 public:
  BagSource(std::unique_ptr<bags::RecordingReader> reader, const bags::BagImportConfig& config,
            const Extrinsics& extrinsics, const InputParams& input)
      : reader_(std::move(reader)),
        config_(config),
        extrinsics_(extrinsics),
        imu_label_(input.imu_label.empty() ? "IMU" : input.imu_label),
        lidar_label_(input.lidar_label.empty() ? "LIDAR" : input.lidar_label),
        stream_(config, callbacks()) {
    reader_->start();
  }

  bool next(RawlogObject& out) override {
    if (!fill()) return false;
    out = std::move(queue_.front());
    queue_.pop_front();
    ++read_;
    return true;
  }

  bool seekToTime(double t) override {
    // Far ahead of what is read: restart the container there (its index skips the rest).
    const double from = t - config_.reorder_window - kLogDelay;
    if (from > newest_) {
      queue_.clear();
      stream_.restart();
      finished_ = at_end_ = false;
      reader_->start(toNs(from));
      newest_ = from;
    }
    while (fill()) {
      if (queue_.front().t && *queue_.front().t >= t) return true;
      queue_.pop_front();
    }
    return false;
  }

  std::optional<double> firstTime() override {
    if (!fill()) return std::nullopt;
    return queue_.front().t;
  }

  // Progress in the recording's log time, shown in seconds ([ns] counted); 0 % where its span is
  // unknown.
  std::uint64_t size() const override {
    return static_cast<std::uint64_t>(std::max<std::int64_t>(reader_->progress().second, 1));
  }
  std::uint64_t position() const override {
    return static_cast<std::uint64_t>(reader_->progress().first);
  }
  mrpt_plugins::ProgressUnit progressUnit() const override { return {"s", 1e9}; }
  std::size_t recordsRead() const override { return read_; }
  std::size_t nextRecord() const override {
    return queue_.empty() ? record_ : queue_.front().index;
  }
  bool atEnd() const override { return at_end_ && queue_.empty(); }

 private:
  /// [s] how long after its stamp a message may be logged (a cloud, once swept and sent).
  static constexpr double kLogDelay = 1.0;

  bags::BagReadCallbacks callbacks() {
    bags::BagReadCallbacks cb;
    cb.imu = [this](const ImuSample& s) {
      push(s.t, mrpt_plugins::imuToObservation(s, imu_label_));
    };
    cb.frame = [this](LidarFrame&& f) {
      push(f.stamp, mrpt_plugins::frameToObservation(f, extrinsics_, lidar_label_));
    };
    return cb;
  }

  void push(double t, mrpt::serialization::CSerializable::Ptr object) {
    RawlogObject r;
    r.index = record_++;
    r.t = t;
    r.object = std::move(object);
    queue_.push_back(std::move(r));
  }

  /// At least one record queued; false at the end.
  bool fill() {
    try {
      while (queue_.empty() && !finished_) {
        if (reader_->step(stream_)) {
          newest_ = std::max(newest_, reader_->lastLogTime());
          continue;
        }
        stream_.finish(reader_->path() + ": " + config_.imu_topic);
        finished_ = true;
      }
    } catch (const std::exception& e) {  // BagError, a corrupt container: one line
      throw InputError(e.what());
    }
    if (queue_.empty()) at_end_ = true;
    return !queue_.empty();
  }

  std::unique_ptr<bags::RecordingReader> reader_;
  bags::BagImportConfig config_;
  Extrinsics extrinsics_;
  std::string imu_label_, lidar_label_;
  bags::ImportStream stream_;
  std::deque<RawlogObject> queue_;
  std::size_t record_ = 0, read_ = 0;
  double newest_ = -std::numeric_limits<double>::infinity();  ///< [s] log time read up to
  bool finished_ = false, at_end_ = false;
};

}  // namespace

bool isRosRecording(const std::string& path) {
  using K = ros2::RecordingKind;
  const K k = ros2::identifyRecording(path);
  return k == K::kMcap || k == K::kSqlite || k == K::kRosbag2Folder || k == K::kRos1Bag;
}

std::unique_ptr<mrpt_plugins::RawlogReader> openInput(const std::string& path,
                                                      const AppConfig& config,
                                                      const mrpt_plugins::RawlogIndexPolicy& index,
                                                      std::vector<std::string>* warnings) {
  using K = ros2::RecordingKind;
  const K kind = ros2::identifyRecording(path);
  // A folder of ROS 2 files without metadata.yaml: the ROS reader's message lists them.
  bool ros2_files = false;
  if (kind == K::kPlainFolder) {
    std::error_code ec;
    for (const auto& f : std::filesystem::directory_iterator(path, ec)) {
      const std::string ext = f.path().extension().string();
      ros2_files = ros2_files || ext == ".db3" || ext == ".mcap";
    }
  }
  if (kind != K::kMcap && kind != K::kSqlite && kind != K::kRosbag2Folder && kind != K::kRos1Bag &&
      !ros2_files)
    return std::make_unique<mrpt_plugins::RawlogReader>(path, index);
  const bags::BagImportConfig& bag = config.bag_import.bag;
  std::unique_ptr<bags::RecordingReader> reader;
  try {
    if (kind == K::kRos1Bag) {
#ifdef FREEINIT_WITH_ROSBAG
      // The index only: each chunk is checked when the window first needs it.
      reader = std::make_unique<ros1::Ros1Reader>(path, bag);
#else
      throw InputError(path +
                       ": a ROS 1 bag, which this build does not read (configure it with "
                       "-DFREEINIT_WITH_ROSBAG=ON)");
#endif
    } else {
      reader = std::make_unique<bags::Ros2Reader>(path, bag);
    }
  } catch (const bags::BagError& e) {
    throw InputError(e.what());
  }
  if (bag.doppler_mode == bags::DopplerMode::kEgoCompensated)
    throw InputError(path +
                     ": [bag_import] doppler_mode = ego_compensated: Free-Init needs the "
                     "raw (relative) Doppler of the sensor");
  std::optional<bags::RecordedExtrinsics> recorded;
  try {
    recorded = reader->staticExtrinsics();
  } catch (const bags::BagError& e) {
    throw InputError(e.what());
  }
  const auto chosen = bags::chooseExtrinsics(config.extrinsics.given_in_ini
                                                 ? std::optional<Extrinsics>(config.core.extrinsics)
                                                 : std::nullopt,
                                             recorded, "[extrinsics]", bag.tf_static_topic, path);
  if (!chosen)
    throw InputError(
        path + ": " + reader->summary().kind + ": no " +
        (bag.tf_static_topic.empty() ? std::string("tf_static_topic") : bag.tf_static_topic) +
        " linking the IMU's frame to the LiDAR's: give the extrinsics in "
        "[extrinsics] (R_bl, p_bl, from_sensor_pose = false)");
  if (!chosen->warning.empty() && warnings != nullptr) warnings->push_back(chosen->warning);
  for (const auto& w : reader->summary().warnings)
    if (warnings != nullptr) warnings->push_back(path + ": " + w);
  return std::make_unique<mrpt_plugins::RawlogReader>(
      path, std::make_unique<BagSource>(std::move(reader), bag, chosen->extrinsics, config.input));
}

}  // namespace freeinit::app_support
