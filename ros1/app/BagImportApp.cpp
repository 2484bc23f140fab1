#include <freeinit/config_section.h>
#include <freeinit/mrpt/ProgressBar.h>
#include <freeinit/mrpt/RawlogWriter.h>
#include <freeinit/mrpt/app_config.h>
#include <freeinit/mrpt/output_set.h>
#include <freeinit/mrpt/stop_signal.h>
#include <freeinit/ros1/BagImportApp.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <iomanip>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace freeinit::mrpt_glue {
namespace {

constexpr const char* kSection = "bag_import";

std::string parseFieldType(std::string_view text, ros1::FieldType& t) {
  try {
    t = ros1::fieldTypeFromName(std::string(text));
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

// "<key>" names a PointCloud2 field ("" = not read, optional fields only), "<key>_type" its
// datatype.
template <class Field>
void addField(config::Section<BagImportSettings>& s, const std::string& key, Field field,
              const std::string& doc) {
  s.text(
       key, [field](auto& x) -> auto& { return field(x).name; }, doc)
      .custom(
          key + "_type", [field](auto& x) -> auto& { return field(x).type; }, "-",
          "int8 | uint8 | int16 | uint16 | int32 | uint32 | float32 | float64",
          std::function<std::string(std::string_view, ros1::FieldType&)>(parseFieldType),
          std::function<std::string(const ros1::FieldType&)>(
              [](const ros1::FieldType& t) { return ros1::fieldTypeName(t); }),
          "datatype of " + key + " in the bag (another type is an error, not a conversion)");
}

std::string fixed(double x, int precision) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(precision) << x;
  return os.str();
}

}  // namespace

const config::Section<BagImportSettings>& bagImportSection() {
  using config::between;
  using S = BagImportSettings;
  static const auto s = [] {
    config::Section<S> sec(kSection,
                           "how to read a ROS1 bag (defaults: the Free-Init / FMCW-LIO release)");
    sec.text(
           "imu_topic", [](auto& x) -> auto& { return x.bag.imu_topic; }, "sensor_msgs/Imu topic",
           true)
        .text(
            "lidar_topic", [](auto& x) -> auto& { return x.bag.lidar_topic; },
            "sensor_msgs/PointCloud2 topic", true);
    addField(
        sec, "x_field", [](auto& x) -> auto& { return x.bag.cloud.x; }, "[m] LiDAR frame x");
    addField(
        sec, "y_field", [](auto& x) -> auto& { return x.bag.cloud.y; }, "[m] LiDAR frame y");
    addField(
        sec, "z_field", [](auto& x) -> auto& { return x.bag.cloud.z; }, "[m] LiDAR frame z");
    addField(
        sec, "doppler_field", [](auto& x) -> auto& { return x.bag.cloud.doppler; },
        "[m/s] per-point Doppler velocity");
    sec.choice(
           "doppler_sign", [](auto& x) -> auto& { return x.bag.cloud.doppler_sign; },
           {{"1", 1.0}, {"-1", -1.0}},
           "1: the field is the range rate (negative approaching); -1: approach is positive")
        .choice(
            "doppler_mode", [](auto& x) -> auto& { return x.bag.doppler_mode; },
            {{"relative", ros1::DopplerMode::kRelative},
             {"ego_compensated", ros1::DopplerMode::kEgoCompensated}},
            "relative (raw range rate) or ego_compensated (refused: Free-Init needs raw "
            "Doppler)");
    addField(
        sec, "time_field", [](auto& x) -> auto& { return x.bag.cloud.time.field; },
        "per-point time");
    sec.number(
           "time_scale", [](auto& x) -> auto& { return x.bag.cloud.time.scale; }, "s per unit",
           config::aboveUpTo(0, 1e3), "1e-9: ns, 1e-6: us, 1: s")
        .flag(
            "time_relative", [](auto& x) -> auto& { return x.bag.cloud.time.relative; },
            "true: offset after the header stamp; false: absolute UNIX time (float64)");
    addField(
        sec, "intensity_field", [](auto& x) -> auto& { return x.bag.cloud.intensity; },
        "optional intensity");
    addField(
        sec, "line_field", [](auto& x) -> auto& { return x.bag.cloud.line; },
        "optional scan line index");
    sec.choice(
           "imu_accel_unit", [](auto& x) -> auto& { return x.bag.imu_accel_in_g; },
           {{"m/s^2", false}, {"g", true}},
           "unit of linear_acceleration (checked against the data: mean |a| ~ 9.81 or ~ 1)")
        .number(
            "lidar_time_offset", [](auto& x) -> auto& { return x.bag.lidar_time_offset; }, "s",
            between(-3600, 3600), "added to LiDAR times to put them on the IMU clock")
        .number(
            "reorder_window", [](auto& x) -> auto& { return x.bag.reorder_window; }, "s",
            between(0, 3600),
            "how late (in stamp time) a message may be recorded and still be put in order")
        .flag(
            "drop_invalid_points", [](auto& x) -> auto& { return x.bag.drop_invalid_points; },
            "drop NaN/inf points (counted); false: error")
        .number(
            "gap_factor", [](auto& x) -> auto& { return x.bag.gap_factor; }, "-",
            config::aboveUpTo(1, 1e6), "report intervals > gap_factor x the median as gaps")
        .number(
            "unit_check_samples", [](auto& x) -> auto& { return x.bag.unit_check_samples; }, "-",
            between(1, 1e6), "first IMU samples whose mean specific force checks imu_accel_unit")
        .text("imu_label", &S::imu_label, "sensorLabel written on the IMU observations", true)
        .text("lidar_label", &S::lidar_label, "sensorLabel written on the point clouds", true)
        .check([](const S& x, const config::Checker& c) {
          if (x.imu_label == x.lidar_label) c.fail("lidar_label", "must differ from imu_label");
          try {
            ros1::validate(x.bag);
          } catch (const std::invalid_argument& e) {  // "key: why"
            const std::string what = e.what();
            const auto colon = what.find(": ");
            c.fail(what.substr(0, colon),
                   colon == std::string::npos ? what : what.substr(colon + 2));
          }
        });
    return sec;
  }();
  return s;
}

BagImportSettings loadBagImportSettings(const std::string& ini_file) {
  const config::IniFile ini = config::IniFile::load(ini_file);
  ini.requireKnownSections({kSection, "extrinsics"});
  BagImportSettings s;
  bagImportSection().load(ini, s);
  // [extrinsics]: the pose keys of the main app's section, required (a bag has no sensor poses;
  // the importer writes them as each cloud's sensorPose).
  LidarPoseParams pose;
  extrinsicsPoseSection().load(ini, pose);
  const config::Checker keys(&ini, "extrinsics");
  if (firstPoseKey(keys).empty())
    keys.fail("R_bl",
              "extrinsics missing: give R_bl (or roll_deg, pitch_deg, yaw_deg) and p_bl; the "
              "importer writes them as each point cloud's sensorPose");
  s.extrinsics = extrinsicsOf(pose, keys);
  return s;
}

int BagImportApp::run(std::ostream& log) {
  settings = loadBagImportSettings(params.config_file);
  if (settings.bag.doppler_mode == ros1::DopplerMode::kEgoCompensated)
    throw std::invalid_argument(
        params.config_file +
        ": [bag_import] doppler_mode = ego_compensated: Free-Init needs the raw (relative) "
        "Doppler of the sensor; ego-compensated Doppler carries no ego velocity, so nothing is "
        "imported");
  std::string out = params.output;
  if (out.empty()) {
    out = params.bag;
    if (const auto dot = out.rfind(".bag"); dot != std::string::npos && dot + 4 == out.size())
      out.resize(dot);
    out += ".rawlog";
  }
  const auto& b = settings.bag;
  log << "Importing " << params.bag << " -> " << out << "\n  IMU " << b.imu_topic
      << (b.imu_accel_in_g ? " (accelerations in g)" : " (m/s^2)") << ", LiDAR " << b.lidar_topic
      << ": Doppler '" << b.cloud.doppler.name << "' x" << b.cloud.doppler_sign << ", time '"
      << b.cloud.time.field.name << "' " << ros1::fieldTypeName(b.cloud.time.field.type) << " x "
      << b.cloud.time.scale << " s " << (b.cloud.time.relative ? "after" : "absolute, not after")
      << " the header stamp; LiDAR time offset " << b.lidar_time_offset << " s\n";

  // The rawlog and its extrinsics file are one set (output_set.h), named after the rawlog.
  const std::filesystem::path stem_path(rawlogStem(out));
  const std::string base = stem_path.filename().string();
  const std::string rawlog_name = std::filesystem::path(out).filename().string();
  const std::string ext = rawlogStem(out) + ".extrinsics.ini";
  OutputSetOptions set_options;
  set_options.owned = {rawlog_name, base + ".extrinsics.ini"};
  set_options.install_last = {rawlog_name};
  OutputSet set(stem_path.parent_path().string(), base, set_options, log);

  RawlogWriter rawlog(set.path(rawlog_name), settings.extrinsics, settings.imu_label,
                      settings.lidar_label);
  ProgressBar bar(log, "  reading", "messages", params.progress_terminal);
  ros1::BagReadCallbacks cb;
  std::size_t count = 0;
  auto poll = [&] {
    if (++count % 256 == 0) throwIfStopRequested();
  };
  cb.imu = [&](const ImuSample& s) {
    poll();
    rawlog.write(s);
  };
  cb.frame = [&](LidarFrame&& f) {
    poll();
    rawlog.write(f);
  };
  if (params.progress) cb.progress = [&](std::size_t d, std::size_t t) { bar.update(d, t); };
  try {
    summary = ros1::readBag(params.bag, b, cb);
  } catch (const std::exception& e) {
    // The reader reports what a callback threw as a bag error: a stop is a stop, a full disk a
    // full disk.
    throwIfStopRequested();
    if (std::string(e.what()).find(std::strerror(ENOSPC)) != std::string::npos)
      throw OutputError(set.describe(rawlog_name, e.what()));
    throw;
  }
  if (params.progress) bar.finish();
  try {
    rawlog.commit();
  } catch (const std::exception& e) {
    throw OutputError(set.describe(rawlog_name, e.what()));
  }
  rawlog_written = out;
  set.write(base + ".extrinsics.ini", [&](const std::string& p) {
    writeExtrinsicsIni(p, settings.extrinsics,
                       "extrinsics of " + out + " (from " + params.config_file +
                           "; also in each point cloud's sensorPose)");
  });
  set.commit();
  summary.print(log);
  log << "Wrote " << out << " (" << rawlog.records() << " records: " << rawlog.imuRecords()
      << " IMU, " << rawlog.frameRecords() << " point clouds, " << summary.points << " points) and "
      << ext << "\nRun: freeinit ini/freeinit.ini " << out << "\n";
  if (summary.imu.skipped() + summary.lidar.skipped() > 0 || summary.invalid_points > 0)
    log << "Warning: " << summary.imu.skipped() + summary.lidar.skipped()
        << " message(s) skipped and " << summary.invalid_points
        << " invalid point(s) dropped (see above)\n";
  if (summary.imu.gaps + summary.lidar.gaps > 0)
    log << "Warning: gaps in the recording (IMU " << summary.imu.gaps << ", LiDAR "
        << summary.lidar.gaps << "); the largest IMU gap is " << fixed(summary.imu.largest_gap, 4)
        << " s\n";
  return 0;
}

}  // namespace freeinit::mrpt_glue
