#include <freeinit/mrpt/ProgressBar.h>
#include <freeinit/mrpt/RawlogWriter.h>
#include <freeinit/mrpt/app_config.h>
#include <freeinit/ros1/BagImportApp.h>
#include <mrpt/config/CConfigFile.h>

#include <cctype>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <ostream>
#include <set>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace freeinit::mrpt_glue {
namespace {

// Strict reader of the [bag_import] section: every key it reads is recorded, and keys it never
// read are errors, so that a typo cannot silently keep a default.
class SectionReader {
 public:
  SectionReader(const mrpt::config::CConfigFile& cfg, std::string file)
      : cfg_(cfg), file_(std::move(file)) {}

  [[noreturn]] void fail(const std::string& key, const std::string& why) const {
    throw std::invalid_argument(file_ + ": [" + kSection + "] " + key + ": " + why);
  }
  bool has(const std::string& key) {
    known_.insert(key);
    return cfg_.keyExists(kSection, key);
  }
  std::string text(const std::string& key) const {
    std::string v = cfg_.read_string(kSection, key, "", false);
    for (const char* c : {";", "#"})
      if (auto p = v.find(c); p != std::string::npos) v.erase(p);
    while (!v.empty() && std::isspace(static_cast<unsigned char>(v.back()))) v.pop_back();
    while (!v.empty() && std::isspace(static_cast<unsigned char>(v.front()))) v.erase(0, 1);
    return v;
  }
  void string(const std::string& key, std::string& x) {
    if (has(key)) x = text(key);
  }
  void number(const std::string& key, double& x) {
    if (!has(key)) return;
    const std::string v = text(key);
    try {
      std::size_t used = 0;
      x = std::stod(v, &used);
      if (used != v.size() || !std::isfinite(x)) throw std::invalid_argument(v);
    } catch (const std::exception&) {
      fail(key, "'" + v + "' is not a finite number");
    }
  }
  void boolean(const std::string& key, bool& x) {
    if (!has(key)) return;
    const std::string v = text(key);
    if (v == "true") {
      x = true;
    } else if (v == "false") {
      x = false;
    } else {
      fail(key, "'" + v + "' is neither true nor false");
    }
  }
  /// "<key>" names the field ("" = not read), "<key>_type" its datatype.
  void field(const std::string& key, ros1::FieldSpec& f) {
    string(key, f.name);
    if (!has(key + "_type")) return;
    try {
      f.type = ros1::fieldTypeFromName(text(key + "_type"));
    } catch (const std::exception& e) {
      fail(key + "_type", e.what());
    }
  }
  /// One of `choices` (the index is returned through x).
  void choice(const std::string& key, const std::vector<std::string>& choices, int& x) {
    if (!has(key)) return;
    const std::string v = text(key);
    for (std::size_t i = 0; i < choices.size(); ++i)
      if (v == choices[i]) {
        x = static_cast<int>(i);
        return;
      }
    std::string all;
    for (const auto& c : choices) all += (all.empty() ? "" : " | ") + c;
    fail(key, "'" + v + "' is not one of " + all);
  }
  void checkUnknownKeys() const {
    std::vector<std::string> keys;
    cfg_.getAllKeys(kSection, keys);
    for (const auto& k : keys)
      if (!known_.count(k)) fail(k, "unknown key");
  }

  static constexpr const char* kSection = "bag_import";

 private:
  const mrpt::config::CConfigFile& cfg_;
  std::string file_;
  std::set<std::string> known_;
};

std::string fixed(double x, int precision) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(precision) << x;
  return os.str();
}

}  // namespace

BagImportSettings loadBagImportSettings(const std::string& ini_file) {
  if (!std::filesystem::is_regular_file(ini_file))
    throw std::invalid_argument(ini_file + ": configuration file not found");
  BagImportSettings s;
  // [extrinsics] with the main app's loader: the same keys, checks and messages.
  const AppConfig app = loadAppConfig(ini_file);
  if (app.extrinsics.from_sensor_pose)
    throw std::invalid_argument(ini_file +
                                ": [extrinsics] from_sensor_pose: a bag has no sensor poses: give "
                                "R_bl (or roll_deg, pitch_deg, yaw_deg) and p_bl");
  s.extrinsics = app.core.extrinsics;

  mrpt::config::CConfigFile cfg(ini_file);
  SectionReader r(cfg, ini_file);
  ros1::BagImportConfig& b = s.bag;
  r.string("imu_topic", b.imu_topic);
  r.string("lidar_topic", b.lidar_topic);
  r.field("x_field", b.cloud.x);
  r.field("y_field", b.cloud.y);
  r.field("z_field", b.cloud.z);
  r.field("doppler_field", b.cloud.doppler);
  r.number("doppler_sign", b.cloud.doppler_sign);
  int mode = 0;
  r.choice("doppler_mode", {"relative", "ego_compensated"}, mode);
  b.doppler_mode = mode == 0 ? ros1::DopplerMode::kRelative : ros1::DopplerMode::kEgoCompensated;
  r.field("time_field", b.cloud.time.field);
  r.number("time_scale", b.cloud.time.scale);
  r.boolean("time_relative", b.cloud.time.relative);
  r.field("intensity_field", b.cloud.intensity);
  r.field("line_field", b.cloud.line);
  int unit = 0;
  r.choice("imu_accel_unit", {"m/s^2", "g"}, unit);
  b.imu_accel_in_g = unit == 1;
  r.number("lidar_time_offset", b.lidar_time_offset);
  r.number("reorder_window", b.reorder_window);
  r.boolean("drop_invalid_points", b.drop_invalid_points);
  r.number("gap_factor", b.gap_factor);
  r.string("imu_label", s.imu_label);
  r.string("lidar_label", s.lidar_label);
  r.checkUnknownKeys();
  try {
    ros1::validate(b);
  } catch (const std::exception& e) {
    throw std::invalid_argument(ini_file + ": [bag_import] " + e.what());
  }
  if (s.imu_label.empty() || s.lidar_label.empty() || s.imu_label == s.lidar_label)
    r.fail("lidar_label", "imu_label and lidar_label must be non-empty and differ");
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

  RawlogWriter rawlog(out, settings.extrinsics, settings.imu_label, settings.lidar_label);
  ProgressBar bar(log, "  reading", "messages", params.progress_terminal);
  ros1::BagReadCallbacks cb;
  cb.imu = [&](const ImuSample& s) { rawlog.write(s); };
  cb.frame = [&](LidarFrame&& f) { rawlog.write(f); };
  if (params.progress) cb.progress = [&](std::size_t d, std::size_t t) { bar.update(d, t); };
  summary = ros1::readBag(params.bag, b, cb);
  if (params.progress) bar.finish();
  rawlog.commit();
  rawlog_written = out;
  const std::string ext = rawlogStem(out) + ".extrinsics.ini";
  writeExtrinsicsIni(ext, settings.extrinsics,
                     "extrinsics of " + out + " (from " + params.config_file +
                         "; also in each point cloud's sensorPose)");
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
