#include <freeinit/app_support/checked_recording.h>
#include <freeinit/app_support/ingest.h>
#include <freeinit/app_support/ingest_sources.h>
#include <freeinit/app_support/recording_source.h>
#include <freeinit/input_checks.h>

#include <algorithm>
#include <map>

namespace freeinit::app_support {

CheckedRecording readRecording(const std::string& path, const AppConfig& config,
                               const mrpt_plugins::RawlogIndexPolicy& index) {
  std::vector<std::string> input_warnings;
  const auto input = openInput(path, config, index, &input_warnings);
  mrpt_plugins::RawlogReader& reader = *input;
  reader.setMaxRecordBytes(static_cast<std::size_t>(config.input.max_record_mb * 1e6));
  ObservationDecoder decoder(config.input);
  RecordChecker checker(config);
  CheckedRecording in;
  in.warnings = input_warnings;
  bool all_ns = true;
  std::map<std::string, int> ignored;  // "class 'label'" -> count
  std::size_t first_imu_record = 0, first_cloud_record = 0;
  auto at = [&](std::size_t record) { return path + ": record " + std::to_string(record) + ": "; };

  auto take = [&](CheckedItem& c) {
    IngestItem& it = c.item;
    if (!c.ok()) throw mrpt_plugins::InputError(at(it.record) + c.problem);
    all_ns = all_ns && it.stamp_ns.has_value();
    if (it.kind == IngestItem::Kind::Imu) {
      if (in.imu.empty()) first_imu_record = it.record;
      in.imu.push_back(it.imu);
      in.imu_stamp_ns.push_back(it.stamp_ns.value_or(0));
    } else if (it.kind == IngestItem::Kind::Frame) {
      if (in.frames.empty()) {
        first_cloud_record = it.record;
        in.sensor_pose_extrinsics = it.frame_extrinsics;
      }
      // The decoder made the frame; nobody else holds it: take its points.
      auto frame = std::const_pointer_cast<LidarFrame>(it.frame);
      in.frames.push_back(frame.use_count() <= 2 ? std::move(*frame) : *frame);
      in.frame_stamp_ns.push_back(it.stamp_ns.value_or(0));
    } else {
      ++ignored[it.what];
    }
  };

  forEachCheckedItem(reader, decoder, checker, take);
  reader.saveIndex();
  if (!all_ns) {
    in.imu_stamp_ns.clear();
    in.frame_stamp_ns.clear();
  }
  in.invalid_points_dropped = checker.invalidPointsDropped();
  for (const auto& [what, n] : ignored)
    in.warnings.push_back("ignored " + std::to_string(n) + " observation(s) of " + what);

  auto seen = [&] {
    std::string s;
    for (const auto& [what, n] : ignored) s += (s.empty() ? "" : ", ") + what;
    return s.empty() ? std::string("none") : s;
  };
  if (in.imu.empty())
    throw mrpt_plugins::InputError(path + ": no CObservationIMU with sensorLabel '" +
                                   config.input.imu_label +
                                   "' ([input] imu_label); other observations: " + seen());
  if (in.frames.empty())
    throw mrpt_plugins::InputError(path + ": no CObservationPointCloud with sensorLabel '" +
                                   config.input.lidar_label +
                                   "' ([input] lidar_label); other observations: " + seen());
  if (in.imu.size() < 2)
    throw mrpt_plugins::InputError(at(first_imu_record) + "a single IMU sample");
  if (const auto problem = input::imuRateProblem(in.imu, config.input.min_imu_rate))
    throw mrpt_plugins::InputError(at(first_imu_record) + *problem);
  if (const auto problem = input::accelUnitProblem(in.imu, config.input.imu_accel_in_g))
    throw mrpt_plugins::InputError(at(first_imu_record) + *problem);

  // The window (from the first IMU sample once the LiDAR has started) must be covered.
  const double t_lidar = in.frames.front().stamp;
  const auto first =
      static_cast<std::size_t>(std::find_if(in.imu.begin(), in.imu.end(),
                                            [&](const ImuSample& s) { return s.t >= t_lidar; }) -
                               in.imu.begin());
  const double window = config.core.window.duration;
  if (window > 0 && !windowLastSample(in.imu, first, window)) {
    std::ostringstream os;
    os << path << ": recording shorter than the window: "
       << (first < in.imu.size() ? in.imu.back().t - in.imu[first].t : 0.0)
       << " s of IMU samples after the first point cloud (record " << first_cloud_record
       << "), [window] duration = " << window << " s";
    throw mrpt_plugins::InputError(os.str());
  }
  return in;
}

}  // namespace freeinit::app_support
