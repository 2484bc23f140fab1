#include <freeinit/atomic_file.h>
#include <freeinit/mrpt/IniLoader.h>
#include <freeinit/mrpt/ProgressBar.h>
#include <freeinit/mrpt/RawlogWriter.h>
#include <freeinit/mrpt/app_config.h>
#include <freeinit/ros1/BagImportApp.h>
#include <mrpt/config/CConfigFile.h>

#include <cmath>
#include <filesystem>
#include <iomanip>
#include <limits>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace freeinit::mrpt_glue {
namespace {

constexpr const char* kSection = "bag_import";

// "<key>" names the field ("" = not read), "<key>_type" its datatype.
void readField(IniLoader& L, const std::string& key, ros1::FieldSpec& f) {
  L(kSection, key, f.name);
  if (!L.has(kSection, key + "_type")) return;
  try {
    f.type = ros1::fieldTypeFromName(L.raw(kSection, key + "_type"));
  } catch (const std::exception& e) {
    L.fail(kSection, key + "_type", e.what());
  }
}

std::string fixed(double x, int precision) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(precision) << x;
  return os.str();
}

void writeFitRow(std::ostream& o, const LidarFrame& f, const ros1::DopplerFit& fit) {
  o << fixed(f.stamp, 6) << "," << fixed(f.stamp + fit.mean_time_offset, 6) << "," << fit.points
    << "," << fit.inliers << "," << (fit.ok ? 1 : 0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto num = [&](double x) { o << "," << (fit.ok ? x : nan); };
  o << std::setprecision(6) << std::defaultfloat;
  for (int i = 0; i < 3; ++i) num(fit.v_l(i));
  for (int i = 0; i < 3; ++i) num(std::sqrt(fit.cov(i, i)));
  num(fit.cov(0, 1));
  num(fit.cov(0, 2));
  num(fit.cov(1, 2));
  num(fit.residual_sigma);
  o << "\n";
}

}  // namespace

const char* const kDopplerFitCsvHeader =
    "stamp,t,points,inliers,ok,v_x,v_y,v_z,sigma_x,sigma_y,sigma_z,cov_xy,cov_xz,cov_yz,"
    "residual_sigma";

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
  IniLoader L(cfg, ini_file);
  ros1::BagImportConfig& b = s.bag;
  L(kSection, "imu_topic", b.imu_topic);
  L(kSection, "lidar_topic", b.lidar_topic);
  readField(L, "x_field", b.cloud.x);
  readField(L, "y_field", b.cloud.y);
  readField(L, "z_field", b.cloud.z);
  readField(L, "doppler_field", b.cloud.doppler);
  L(kSection, "doppler_sign", b.cloud.doppler_sign);
  b.doppler_mode = L.choice(kSection, "doppler_mode", {"relative", "ego_compensated"}, 0) == 0
                       ? ros1::DopplerMode::kRelative
                       : ros1::DopplerMode::kEgoCompensated;
  readField(L, "time_field", b.cloud.time.field);
  L(kSection, "time_scale", b.cloud.time.scale);
  L(kSection, "time_relative", b.cloud.time.relative);
  L(kSection, "frame_duration", b.cloud.time.frame_duration);
  b.stamp_source = static_cast<ros1::StampSource>(L.choice(kSection, "stamp_source",
                                                           {"header", "trigger", "bag_time"},
                                                           static_cast<int>(b.stamp_source)));
  L(kSection, "trigger_topic", b.trigger_topic);
  readField(L, "intensity_field", b.cloud.intensity);
  readField(L, "line_field", b.cloud.line);
  b.imu_accel_in_g = L.choice(kSection, "imu_accel_unit", {"m/s^2", "g"}, 0) == 1;
  L(kSection, "lidar_time_offset", b.lidar_time_offset);
  L(kSection, "reorder_window", b.reorder_window);
  L(kSection, "drop_invalid_points", b.drop_invalid_points);
  L(kSection, "gap_factor", b.gap_factor);
  L(kSection, "imu_label", s.imu_label);
  L(kSection, "lidar_label", s.lidar_label);
  ros1::DopplerFitParams& f = s.doppler_fit;
  L("doppler_fit", "min_range", f.min_range);
  L("doppler_fit", "inlier_threshold", f.inlier_threshold);
  L("doppler_fit", "sigma_floor", f.sigma_floor);
  L("doppler_fit", "min_inlier_fraction", f.min_inlier_fraction);
  L.checkUnknownKeys();
  if (!(f.min_range >= 0)) L.fail("doppler_fit", "min_range", "must be >= 0");
  if (!(f.inlier_threshold > 0)) L.fail("doppler_fit", "inlier_threshold", "must be > 0");
  if (!(f.sigma_floor >= 0)) L.fail("doppler_fit", "sigma_floor", "must be >= 0");
  if (!(f.min_inlier_fraction >= 0 && f.min_inlier_fraction <= 1))
    L.fail("doppler_fit", "min_inlier_fraction", "must be in [0, 1]");
  try {
    ros1::validate(b);
  } catch (const std::exception& e) {
    throw std::invalid_argument(ini_file + ": [bag_import] " + e.what());
  }
  if (s.imu_label.empty() || s.lidar_label.empty() || s.imu_label == s.lidar_label)
    L.fail(kSection, "lidar_label", "imu_label and lidar_label must be non-empty and differ");
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
  const std::string time = b.cloud.time.field.name.empty()
                               ? "no per-point time (points spread over " +
                                     fixed(b.cloud.time.frame_duration, 4) + " s in point order)"
                               : "time '" + b.cloud.time.field.name + "' " +
                                     ros1::fieldTypeName(b.cloud.time.field.type) + " x " +
                                     fixed(b.cloud.time.scale, 12) + " s " +
                                     (b.cloud.time.relative ? "after" : "absolute, not after") +
                                     " the scan stamp";
  log << "Importing " << params.bag << " -> " << out << "\n  IMU " << b.imu_topic
      << (b.imu_accel_in_g ? " (accelerations in g)" : " (m/s^2)") << ", LiDAR " << b.lidar_topic
      << ": Doppler '" << b.cloud.doppler.name << "' x" << b.cloud.doppler_sign << ", " << time
      << "\n  scan stamps: " << ros1::stampSourceName(b.stamp_source)
      << (b.stamp_source == ros1::StampSource::kTrigger ? " " + b.trigger_topic : std::string())
      << ", + " << fixed(b.lidar_time_offset, 6) << " s to the IMU clock\n";

  RawlogWriter rawlog(out, settings.extrinsics, settings.imu_label, settings.lidar_label);
  ProgressBar bar(log, "  reading", "messages", params.progress_terminal);
  ros1::BagReadCallbacks cb;
  cb.imu = [&](const ImuSample& s) { rawlog.write(s); };
  std::ostringstream fits;
  if (!params.doppler_fit_csv.empty()) fits << kDopplerFitCsvHeader << "\n";
  cb.frame = [&](LidarFrame&& f) {
    if (!params.doppler_fit_csv.empty())
      writeFitRow(fits, f, ros1::fitScanVelocity(f.points, settings.doppler_fit));
    rawlog.write(f);
  };
  if (params.progress) cb.progress = [&](std::size_t d, std::size_t t) { bar.update(d, t); };
  summary = ros1::readBag(params.bag, b, cb);
  if (params.progress) bar.finish();
  rawlog.commit();
  rawlog_written = out;
  const std::string ext = rawlogStem(out) + ".extrinsics.ini";
  writeExtrinsicsIni(ext, settings.extrinsics,
                     "extrinsics of " + out + " (from " + params.config_file +
                         "; also in each point cloud's sensorPose)");
  if (!params.doppler_fit_csv.empty()) {
    writeFileAtomically(params.doppler_fit_csv, [&](std::ostream& o) { o << fits.str(); });
    log << "Wrote " << params.doppler_fit_csv << " (per-scan Doppler-only velocity fits)\n";
  }
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
