#include "bag_import_app.h"

#include <freeinit/app_support/app_config.h>
#include <freeinit/app_support/command_line.h>
#include <freeinit/app_support/output_set.h>
#include <freeinit/app_support/progress_bar.h>
#include <freeinit/app_support/stop_signal.h>
#include <freeinit/io/atomic_file.h>
#include <freeinit/io/config_section.h>
#include <freeinit/mrpt_plugins/rawlog_writer.h>
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
/// [s] the largest clock offset: ROS1 times are uint32 seconds, so two of them differ by less
/// than 2^32 s (a scan stamp from a clock since boot against bag times since 1970 is ~1.7e9 s).
constexpr double kMaxClockOffset = 4294967296.0;

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
        "per-point time (empty: none, see frame_duration)");
    sec.number(
           "time_scale", [](auto& x) -> auto& { return x.bag.cloud.time.scale; }, "s per unit",
           config::aboveUpTo(0, 1e3), "1e-9: ns, 1e-6: us, 1: s")
        .flag(
            "time_relative", [](auto& x) -> auto& { return x.bag.cloud.time.relative; },
            "true: offset after the scan stamp; false: absolute UNIX time (float64)")
        .number(
            "frame_duration", [](auto& x) -> auto& { return x.bag.cloud.time.frame_duration; }, "s",
            between(0, 10),
            "without a time field: the span after the scan stamp the points are spread over, in "
            "point order (0: all at the scan stamp)")
        .choice(
            "stamp_source", [](auto& x) -> auto& { return x.bag.stamp_source; },
            {{"header", ros1::StampSource::kHeader},
             {"trigger", ros1::StampSource::kTrigger},
             {"bag_time", ros1::StampSource::kBagTime}},
            "scan stamp: the cloud's header stamp, the stamp of the trigger_topic message with "
            "the cloud's seq, or the time the bag recorded the cloud")
        .text(
            "trigger_topic", [](auto& x) -> auto& { return x.bag.trigger_topic; },
            "std_msgs/Header topic of the scan starts (only with stamp_source = trigger)");
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
            between(-kMaxClockOffset, kMaxClockOffset),
            "added to every scan stamp to put it on the IMU clock (bag times are often days "
            "off)")
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
        .text("freeinit_config", &S::freeinit_config,
              "the freeinit configuration made for this sensor, relative to this INI's folder, "
              "suggested after the import (empty: the defaults suit it)",
              false)
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
  bagImportSection().load(ini, s);
  dopplerFitSection().load(ini, s.doppler_fit);
  // [extrinsics]: the pose keys of the main app's section, required (a bag has no sensor poses;
  // the importer writes them as each cloud's sensorPose).
  app_support::LidarPoseParams pose;
  app_support::extrinsicsPoseSection().load(ini, pose);
  const config::Checker keys(&ini, "extrinsics");
  if (app_support::firstPoseKey(keys).empty())
    keys.fail("R_bl",
              "extrinsics missing: give R_bl (or roll_deg, pitch_deg, yaw_deg) and p_bl; the "
              "importer writes them as each point cloud's sensorPose");
  s.extrinsics = app_support::extrinsicsOf(pose, keys);
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
    summary = ros1::readBag(params.bag, b, cb);
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
                                     "extrinsics of " + out + " (from " + params.config_file +
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
        << summary.lidar.gaps << "); the largest IMU gap is " << fixed(summary.imu.largest_gap, 4)
        << " s\n";
  return 0;
}

int BagImportApp::main(int argc, char** argv) {
  app_support::CommandLine cli(
      "freeinit-import-bag",
      "a ROS1 bag (sensor_msgs/Imu + sensor_msgs/PointCloud2 with per-point "
      "Doppler and time) to a rawlog for freeinit");
  const auto& bag = cli.positional("input.bag", "input ROS1 bag");
  const auto& config = cli.requiredText(
      "c", "config",
      "INI with [bag_import], [extrinsics] and optionally [doppler_fit] (see ini/import_bag.ini)",
      "FILE");
  const auto& out = cli.text("o", "out", "output rawlog", "", "FILE", "<bag>.rawlog");
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
