#include "bag_import_app.h"

#include <freeinit/app_support/app_config.h>
#include <freeinit/app_support/command_line.h>
#include <freeinit/app_support/output_set.h>
#include <freeinit/app_support/progress_bar.h>
#include <freeinit/app_support/stop_signal.h>
#include <freeinit/bags/ros2_import.h>
#include <freeinit/io/atomic_file.h>
#include <freeinit/io/config_section.h>
#include <freeinit/io/number_format.h>
#include <freeinit/mrpt_plugins/rawlog_writer.h>
#include <freeinit/ros2/open_recording.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <limits>
#include <optional>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace freeinit::apps {
namespace {

constexpr const char* kSection = "bag_import";

void writeFitRow(std::ostream& o, const LidarFrame& f, const ros1::DopplerFit& fit) {
  o << formatFixed(f.stamp, 6) << "," << formatFixed(f.stamp + fit.mean_time_offset, 6) << ","
    << fit.points << "," << fit.inliers << "," << (fit.ok ? 1 : 0);
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

const config::Section<ros1::DopplerFitParams>& dopplerFitSection() {
  using config::between;
  using P = ros1::DopplerFitParams;
  static const auto s =
      config::Section<P>("doppler_fit",
                         "the per-scan Doppler-only velocity fits of --doppler-fit-csv")
          .number("min_range", &P::min_range, "m", between(0, 1000), "closer points are not used")
          .number("inlier_threshold", &P::inlier_threshold, "m/s", config::aboveUpTo(0, 100),
                  "largest |residual| of an inlier")
          .number("sigma_floor", &P::sigma_floor, "m/s", between(0, 10),
                  "lower bound of the per-point residual std (quantized Doppler: step/sqrt(12))")
          .number("min_inlier_fraction", &P::min_inlier_fraction, "-", between(0, 1),
                  "fewer inliers than this fraction of the points: no fit");
  return s;
}

BagImportSettings loadBagImportSettings(const std::string& ini_file) {
  const config::IniFile ini = config::IniFile::load(ini_file);
  ini.requireKnownSections({kSection, dopplerFitSection().name(), "extrinsics"});
  BagImportSettings s;
  bags::importSection().load(ini, s);
  dopplerFitSection().load(ini, s.doppler_fit);
  // [extrinsics]: the pose keys of the main app's section, required (a bag has no sensor poses;
  // the importer writes them as each cloud's sensorPose).
  app_support::LidarPoseParams pose;
  app_support::extrinsicsPoseSection().load(ini, pose);
  // Optional: the recording's /tf_static may give them (checked in run()).
  const config::Checker keys(&ini, "extrinsics");
  s.extrinsics_given = !app_support::firstPoseKey(keys).empty();
  if (s.extrinsics_given) s.extrinsics = app_support::extrinsicsOf(pose, keys);
  return s;
}

std::string defaultRawlogName(const std::string& input) {
  std::string out = input;
  while (out.size() > 1 && out.back() == '/') out.pop_back();
  if (!std::filesystem::is_directory(out))
    for (const char* ext : {".bag", ".mcap", ".db3"}) {
      const std::string e(ext);
      if (out.size() > e.size() && out.compare(out.size() - e.size(), e.size(), e) == 0) {
        out.resize(out.size() - e.size());
        break;
      }
    }
  return out + ".rawlog";
}

namespace {

bool isRos2(ros2::RecordingKind k) {
  return k == ros2::RecordingKind::kMcap || k == ros2::RecordingKind::kSqlite ||
         k == ros2::RecordingKind::kRosbag2Folder;
}

}  // namespace

int BagImportApp::run(std::ostream& log) {
  settings = loadBagImportSettings(params.config_file);
  if (settings.bag.doppler_mode == ros1::DopplerMode::kEgoCompensated)
    throw std::invalid_argument(
        params.config_file +
        ": [bag_import] doppler_mode = ego_compensated: Free-Init needs the raw (relative) "
        "Doppler of the sensor; ego-compensated Doppler carries no ego velocity, so nothing is "
        "imported");
  std::string out = params.output.empty() ? defaultRawlogName(params.bag) : params.output;
  const auto& b = settings.bag;
  const ros2::RecordingKind kind = ros2::identifyRecording(params.bag);
  const bool ros2_input = isRos2(kind) || kind == ros2::RecordingKind::kPlainFolder;
  if (ros2_input) {
    // Opened once here for its topics and extrinsics (the read opens it again: cheap with an
    // index).
    recorded_extrinsics = bags::Ros2Reader(params.bag, b).staticExtrinsics();
  } else if (kind == ros2::RecordingKind::kRos1Bag) {
    recorded_extrinsics = ros1::readStaticExtrinsics(params.bag, b);
  }
  chooseExtrinsics();
  const std::string time =
      b.cloud.time.field.name.empty()
          ? "no per-point time (points spread over " + formatFixed(b.cloud.time.frame_duration, 4) +
                " s in point order)"
          : "time '" + b.cloud.time.field.name + "' " +
                ros1::fieldTypeName(b.cloud.time.field.type) + " x " +
                formatFixed(b.cloud.time.scale, 12) + " s " +
                (b.cloud.time.relative ? "after" : "absolute, not after") + " the scan stamp";
  log << "Importing " << params.bag << " -> " << out << "\n  extrinsics from "
      << settings.extrinsics_source << "\n  IMU " << b.imu_topic
      << (b.imu_accel_in_g ? " (accelerations in g)" : " (m/s^2)") << ", LiDAR " << b.lidar_topic
      << ": Doppler '" << b.cloud.doppler.name << "' x" << b.cloud.doppler_sign << ", " << time
      << "\n  scan stamps: " << ros1::stampSourceName(b.stamp_source)
      << (b.stamp_source == ros1::StampSource::kTrigger ? " " + b.trigger_topic : std::string())
      << ", + " << formatFixed(b.lidar_time_offset, 6) << " s to the IMU clock\n";

  // The rawlog and its extrinsics file are one set (output_set.h), named after the rawlog.
  const std::filesystem::path stem_path(mrpt_plugins::rawlogStem(out));
  const std::string base = stem_path.filename().string();
  const std::string rawlog_name = std::filesystem::path(out).filename().string();
  const std::string ext = mrpt_plugins::rawlogStem(out) + ".extrinsics.ini";
  app_support::OutputSetOptions set_options;
  set_options.owned = {rawlog_name, base + ".extrinsics.ini"};
  set_options.install_last = {rawlog_name};
  app_support::OutputSet set(stem_path.parent_path().string(), base, set_options, log);
  // The fits table, where the user wants it: a set of its own.
  std::optional<app_support::OutputSet> fit_set;
  if (!params.doppler_fit_csv.empty()) {
    const std::filesystem::path fit(params.doppler_fit_csv);
    app_support::OutputSetOptions fit_options;
    fit_options.owned = {fit.filename().string()};
    fit_set.emplace(fit.parent_path().string(), fit.filename().string(), fit_options, log);
  }

  mrpt_plugins::RawlogWriter rawlog(set.path(rawlog_name), settings.extrinsics, settings.imu_label,
                                    settings.lidar_label);
  app_support::ProgressBar bar(log, "  reading", "messages", params.progress_terminal);
  ros1::BagReadCallbacks cb;
  std::size_t count = 0;
  auto poll = [&] {
    if (++count % 256 == 0) app_support::throwIfStopRequested();
  };
  cb.imu = [&](const ImuSample& s) {
    poll();
    rawlog.write(s);
  };
  std::ostringstream fits;
  if (!params.doppler_fit_csv.empty()) fits << kDopplerFitCsvHeader << "\n";
  cb.frame = [&](LidarFrame&& f) {
    poll();
    if (!params.doppler_fit_csv.empty())
      writeFitRow(fits, f, ros1::fitScanVelocity(f.points, settings.doppler_fit));
    rawlog.write(f);
  };
  if (params.progress) cb.progress = [&](std::size_t d, std::size_t t) { bar.update(d, t); };
  try {
    summary =
        ros2_input ? bags::readRos2Recording(params.bag, b, cb) : ros1::readBag(params.bag, b, cb);
  } catch (const std::exception& e) {
    // The reader reports what a callback threw as a bag error: a stop is a stop, a full disk a
    // full disk.
    app_support::throwIfStopRequested();
    if (std::string(e.what()).find(std::strerror(ENOSPC)) != std::string::npos)
      throw app_support::OutputError(set.describe(rawlog_name, e.what()));
    throw;
  }
  if (params.progress) bar.finish();
  try {
    rawlog.commit();
  } catch (const std::exception& e) {
    throw app_support::OutputError(set.describe(rawlog_name, e.what()));
  }
  rawlog_written = out;
  set.write(base + ".extrinsics.ini", [&](const std::string& p) {
    mrpt_plugins::writeExtrinsicsIni(p, settings.extrinsics,
                                     "extrinsics of " + out + " (from " +
                                         settings.extrinsics_source +
                                         "; also in each point cloud's sensorPose)");
  });
  if (fit_set) {
    const std::string name = std::filesystem::path(params.doppler_fit_csv).filename().string();
    fit_set->write(name, [&](const std::string& p) {
      writeFileAtomically(p, [&](std::ostream& o) { o << fits.str(); });
    });
  }
  set.commit();
  if (fit_set) {
    fit_set->commit();
    log << "Wrote " << params.doppler_fit_csv << " (per-scan Doppler-only velocity fits)\n";
  }
  summary.print(log);
  if (!extrinsics_warning.empty()) log << "Warning: " << extrinsics_warning << "\n";
  log << "Wrote " << out << " (" << rawlog.records() << " records: " << rawlog.imuRecords()
      << " IMU, " << rawlog.frameRecords() << " point clouds, " << summary.points << " points) and "
      << ext << "\n";
  if (settings.freeinit_config.empty())
    log << "Run: freeinit " << out << "   (the default configuration; freeinit <config.ini> " << out
        << " for another)\n";
  else
    log << "Run: freeinit "
        << (std::filesystem::path(params.config_file).parent_path() / settings.freeinit_config)
               .lexically_normal()
               .string()
        << " " << out << "   (the configuration for this sensor: [bag_import] freeinit_config of "
        << params.config_file << ")\n";
  if (summary.imu.skipped() + summary.lidar.skipped() > 0 || summary.invalid_points > 0)
    log << "Warning: " << summary.imu.skipped() + summary.lidar.skipped()
        << " message(s) skipped and " << summary.invalid_points
        << " invalid point(s) dropped (see above)\n";
  if (summary.imu.gaps + summary.lidar.gaps > 0)
    log << "Warning: gaps in the recording (IMU " << summary.imu.gaps << ", LiDAR "
        << summary.lidar.gaps << "); the largest IMU gap is "
        << formatFixed(summary.imu.largest_gap, 4) << " s\n";
  return 0;
}

void BagImportApp::chooseExtrinsics() {
  const std::string tf = settings.bag.tf_static_topic;
  extrinsics_warning.clear();
  const auto chosen = bags::chooseExtrinsics(
      settings.extrinsics_given ? std::optional<Extrinsics>(settings.extrinsics) : std::nullopt,
      recorded_extrinsics, params.config_file + " [extrinsics]", tf, params.bag);
  if (!chosen)
    throw std::invalid_argument(
        params.config_file + ": [extrinsics] R_bl: extrinsics missing, and " + params.bag +
        " has " + (tf.empty() ? std::string("tf_static_topic off") : "no " + tf) +
        " linking the IMU's frame to the LiDAR's: give R_bl (or roll_deg, pitch_deg, yaw_deg) "
        "and p_bl; the importer writes them as each point cloud's sensorPose");
  settings.extrinsics = chosen->extrinsics;
  settings.extrinsics_source = chosen->source;
  extrinsics_warning = chosen->warning;
}

int BagImportApp::main(int argc, char** argv) {
  app_support::CommandLine cli(
      "freeinit-import-bag",
      "a ROS recording (sensor_msgs/Imu + sensor_msgs/PointCloud2 with per-point "
      "Doppler and time) to a rawlog for freeinit: a ROS 1 bag, an MCAP file, a rosbag2 folder "
      "or a .db3");
  const auto& bag =
      cli.positional("input", "input recording: ROS 1 .bag, ROS 2 .mcap, rosbag2 folder or .db3");
  const auto& config = cli.requiredText(
      "c", "config",
      "INI with [bag_import], [extrinsics] and optionally [doppler_fit] (see ini/import_bag.ini)",
      "FILE");
  const auto& out = cli.text("o", "out", "output rawlog", "", "FILE", "<input>.rawlog");
  const auto& fit_csv = cli.text("", "doppler-fit-csv",
                                 "also write each imported scan's sensor velocity fitted from its "
                                 "Doppler alone (no IMU; [doppler_fit] of the INI) to FILE",
                                 "", "FILE", "none");
  const auto& quiet = cli.flag("q", "quiet", "no progress bar");
  if (const auto code = cli.parse(argc, argv)) return *code;
  return app_support::runMain(cli.program(), [&] {
    BagImportApp app;
    app.params.bag = bag.value;
    app.params.config_file = config.value;
    app.params.output = out.value;
    app.params.doppler_fit_csv = fit_csv.value;
    app.params.progress = !quiet.value;
    app.params.progress_terminal = isatty(STDOUT_FILENO) != 0;
    return app.run(std::cout);
  });
}

}  // namespace freeinit::apps
