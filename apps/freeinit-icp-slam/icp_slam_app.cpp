#include "icp_slam_app.h"

#include <freeinit/app_support/checked_recording.h>
#include <freeinit/app_support/command_line.h>
#include <freeinit/app_support/map_export.h>
#include <freeinit/app_support/output_set.h>
#include <freeinit/app_support/output_writers.h>
#include <freeinit/app_support/result_files.h>
#include <freeinit/app_support/snapshots.h>
#include <freeinit/app_support/stop_signal.h>
#include <freeinit/doppler_inertial_odometry.h>
#include <freeinit/free_init.h>
#include <freeinit/mrpt_plugins/conversions.h>
#include <freeinit/mrpt_plugins/rawlog_reader.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/io/vector_loadsave.h>
#include <mrpt/maps/CPointsMap.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/poses/CPoint2D.h>
#include <mrpt/slam/CMetricMapBuilderICP.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <ostream>
#include <sstream>

namespace freeinit::apps {
namespace {

// The files this app writes: in <out>, in <out>/<mode>/ and in the export folder (<mode>.*).
constexpr const char* kSeedIniFile = "icp_slam_seed.ini";
constexpr const char* kOdometryAloneFile = "odometry_alone_tum.txt";
constexpr const char* kResultsFile = "results.txt";
constexpr const char* kPictureFile = "trajectories.png";
constexpr const char* kMapFile = "_finalmap_.simplemap";
constexpr const char* kStepLogFile = "log_estimated_path.txt";
constexpr const char* kPathFile = "estimated_path_tum.txt";
constexpr const char* kErrorsFile = "errors_wrt_gt.ini";

const char* kMappingSection = "MappingApplication";

/// Whether one odometry reading at the seed pose would stop icp-slam from ever correcting: after
/// an odometry reading, CMetricMapBuilderICP 2.5.8 skips ICP until the odometry shows
/// min(localization, insertion) distance or angle since the last correction (at the origin, at
/// first), and a lone reading never shows more than the seed pose itself.
bool seedReadingBlocksIcp(const app_support::IcpSeed& seed,
                          const mrpt::slam::CMetricMapBuilderICP::TConfigParams& o) {
  const auto& m = seed.pose.mean;
  return std::hypot(m.x(), m.y()) < std::min(o.localizationLinDistance, o.insertionLinDistance) &&
         std::abs(m.phi()) < std::min(o.localizationAngDistance, o.insertionAngDistance);
}

/// The observations icp-slam processes in a mode, in time order, after the static map. Seeded:
/// one odometry reading with the seed pose in w and its velocity (icp-slam extrapolates each
/// scan's first guess from it, for up to 1 s) unless `seed_reading` is false, then the scans
/// after the state time. Odometry: a reading at the state time and one at every scan.
std::vector<mrpt::obs::CObservation::Ptr> icpSlamObservations(
    app_support::IcpSeedMode mode,
    const std::vector<mrpt::obs::CObservation2DRangeScan::Ptr>& scans,
    const app_support::IcpSeed* seed, const std::vector<OdometrySample>& odometry,
    bool seed_reading) {
  std::vector<mrpt::obs::CObservation::Ptr> out;
  if (mode == app_support::IcpSeedMode::Plain) {
    out.assign(scans.begin(), scans.end());
    return out;
  }
  const double t0 = seed->timestamp;
  if (mode == app_support::IcpSeedMode::Odometry) {
    out.push_back(app_support::odometryAt(odometry, t0, mrpt::math::TPose2D()));
  } else if (seed_reading) {
    auto first = mrpt::obs::CObservationOdometry::Create();
    first->sensorLabel = "FREEINIT_ODOMETRY";
    first->timestamp = mrpt_plugins::fromUnix(t0);
    first->odometry = seed->pose.mean;
    first->hasVelocities = true;
    first->velocityLocal = seed->velocity_local;
    out.push_back(first);
  }
  for (const auto& s : scans) {
    const double t = mrpt_plugins::toUnix(s->timestamp);
    if (t <= t0) continue;
    if (mode == app_support::IcpSeedMode::Odometry) {
      if (t > odometry.back().t) break;  // the odometry ends with the IMU data
      out.push_back(app_support::odometryAt(odometry, t, mrpt::math::TPose2D()));
    }
    out.push_back(s);
  }
  return out;
}

struct BuilderOutput {
  std::vector<app_support::PlanarPathSample> path;
  mrpt::maps::CSimpleMap map;
  std::vector<float> map_x, map_y;
  std::string step_log;  ///< the stock app's log_estimated_path.txt: "step x y yaw"
};

/// CMetricMapBuilderICP configured exactly as the stock app configures it, initialized with the
/// seed's map (if any) and the pose prior (if given).
BuilderOutput runBuilder(const mrpt::config::CConfigFileBase& ini, const app_support::IcpSeed* seed,
                         const mrpt::poses::CPosePDFGaussian* prior,
                         const std::vector<mrpt::obs::CObservation::Ptr>& observations) {
  mrpt::slam::CMetricMapBuilderICP builder;
  builder.setVerbosityLevel(mrpt::system::LVL_ERROR);
  builder.ICP_options.loadFromConfigFile(ini, kMappingSection);
  builder.ICP_params.loadFromConfigFile(ini, "ICP");
  builder.initialize(seed ? seed->map : mrpt::maps::CSimpleMap(), prior);
  builder.options.alwaysInsertByClass.fromString(
      ini.read_string(kMappingSection, "alwaysInsertByClass", ""));
  BuilderOutput out;
  std::ostringstream steps;
  int step = 0;
  for (const auto& obs : observations) {
    app_support::throwIfStopRequested();
    builder.processObservation(obs);
    const auto pose = builder.getCurrentPoseEstimation()->getMeanVal();
    steps << step++ << " " << std::fixed << std::setprecision(6) << pose.x() << " " << pose.y()
          << " " << pose.yaw() << "\n";
    if (IS_CLASS(*obs, mrpt::obs::CObservation2DRangeScan))
      out.path.push_back({mrpt_plugins::toUnix(obs->timestamp),
                          mrpt::math::TPose2D(pose.x(), pose.y(), pose.yaw())});
  }
  out.step_log = steps.str();
  builder.getCurrentlyBuiltMap(out.map);
  if (auto pts = builder.getCurrentlyBuiltMetricMap()->mapByClass<mrpt::maps::CPointsMap>())
    pts->getAllPoints(out.map_x, out.map_y);
  return out;
}

void writeTumPlanar(const std::string& path,
                    const std::vector<app_support::PlanarPathSample>& samples) {
  writeFileAtomically(path, [&](std::ostream& o) {
    o << "# icp-slam path: timestamp x y z qx qy qz qw (robot = body, planar)\n"
      << std::fixed << std::setprecision(6);
    for (const auto& s : samples)
      o << s.t << " " << s.pose.x << " " << s.pose.y << " 0 0 0 " << std::sin(0.5 * s.pose.phi)
        << " " << std::cos(0.5 * s.pose.phi) << "\n";
  });
}

/// The prior as handed over, with its covariance (CMetricMapBuilderICP 2.5.8 keeps the mean only).
void writeSeedIni(const std::string& path, const app_support::IcpSeed& seed) {
  writeFileAtomically(path, [&](std::ostream& o) {
    const auto& m = seed.pose.mean;
    o << "; Free-Init's initial state as icp-slam's prior: SE(2) pose of the body in w, its\n"
         "; covariance (x, y, yaw marginal of the 18x18 state covariance) and the velocity\n"
         "[icp_slam_seed]\n"
      << std::setprecision(17) << "timestamp = " << seed.timestamp << "   ; [s] UNIX\n"
      << std::setprecision(9) << "pose = " << m.x() << " " << m.y() << " " << m.phi()
      << "   ; x [m], y [m], yaw [rad]\ncov = ";
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) o << seed.pose.cov(r, c) << (r * 3 + c < 8 ? " " : "");
    o << "   ; 3x3 row-major\nvelocity_local = " << seed.velocity_local.vx << " "
      << seed.velocity_local.vy << " " << seed.velocity_local.omega
      << "   ; vx [m/s], vy [m/s], omega [rad/s] in the robot frame\nstatic_map_points = "
      << seed.map_points << "\n";
  });
}

/// One panel per run: its map and path in the truth frame, anchored where the comparison starts.
void renderRuns(const std::string& png, const std::string& title,
                const std::vector<IcpSlamRun>& runs,
                const std::vector<app_support::TruthSample>& truth, double t_state, int width,
                int height) {
  std::vector<app_support::TopViewPanel> panels;
  for (const auto& r : runs) {
    // With the truth, everything in its frame, anchored where the comparison starts (the first
    // scan after the state time): the picture shows how each run leaves the truth from a common
    // start. (The ATE uses the best alignment over the whole path instead.) Without it, in w.
    mrpt::poses::CPose2D A;
    for (const auto& ps : r.path) {
      const auto gt = ps.t >= t_state ? app_support::truthAt(truth, ps.t) : std::nullopt;
      if (!gt) continue;
      A = mrpt::poses::CPose2D(app_support::planarPose(gt->q_wb, gt->p_w)) +
          (mrpt::poses::CPose2D() - mrpt::poses::CPose2D(ps.pose));
      break;
    }
    app_support::TopViewPanel p;
    std::ostringstream t;
    t << "icp-slam " << toString(r.mode) << ":  " << r.keyframes << " keyframes";
    if (r.errors)
      t << ", ATE " << std::fixed << std::setprecision(2) << r.errors->ate_rmse << " m, end-point "
        << r.errors->end_point << " m";
    p.title = t.str();
    for (std::size_t k = 0; k < r.map_x.size(); ++k) {
      const auto q = A + mrpt::poses::CPoint2D(r.map_x[k], r.map_y[k]);
      p.map_x.push_back(static_cast<float>(q.x()));
      p.map_y.push_back(static_cast<float>(q.y()));
    }
    for (const auto& ps : r.path) {
      const auto q = A + mrpt::poses::CPoint2D(ps.pose.x, ps.pose.y);
      p.path.emplace_back(q.x(), q.y(), 0.0);
      if (const auto gt = app_support::truthAt(truth, ps.t)) p.truth.push_back(gt->p_w);
    }
    panels.push_back(std::move(p));
  }
  app_support::renderTopViewPanels(png, title, panels, width, height);
}

/// The icp-slam INI: its text (the export copies it) and MRPT's parse of it, checked for the
/// stock app's sections.
struct IcpIni {
  std::string text;
  mrpt::config::CConfigFileMemory ini;
};

void loadIcpIni(const std::string& path, IcpIni& out) {
  if (!std::filesystem::is_regular_file(path)) throw std::invalid_argument(path + ": no such file");
  out.text = mrpt::io::file_get_contents(path);
  // MRPT's own parser reads the stock app's sections ([MappingApplication], [ICP]); its errors
  // name neither the file nor the line's text, and carry a backtrace.
  try {
    out.ini.setContent(out.text);
  } catch (const std::exception& e) {
    std::string why = e.what();
    if (const auto m = why.find("Message:"); m != std::string::npos) why.erase(0, m + 8);
    why.erase(0, why.find_first_not_of(' '));
    why = why.substr(0, why.find('\n'));
    throw std::invalid_argument(path + ": cannot be read as an icp-slam INI: " + why);
  }
  if (!out.ini.sectionExists(kMappingSection) || !out.ini.sectionExists("ICP"))
    throw std::invalid_argument(path +
                                ": needs the [MappingApplication] and [ICP] "
                                "sections of the icp-slam app");
}

/// The outputs: one set per folder (output_set.h), installed when the run is complete; a run
/// that fails leaves no output of ours in either folder, nor one of an earlier run.
struct IcpOutputs {
  app_support::OutputSet out;
  std::optional<app_support::OutputSet>
      own_export;                             ///< an export folder other than the output folder
  app_support::OutputSet* exports = nullptr;  ///< where the export goes (nullptr: no export)

  IcpOutputs(const IcpSlamAppParams& params, std::ostream& log)
      : out(params.out_dir, "", app_support::folderSetOptions(), log) {
    if (params.export_dir.empty()) return;
    if (std::filesystem::weakly_canonical(params.export_dir) !=
        std::filesystem::weakly_canonical(params.out_dir))
      own_export.emplace(params.export_dir, "", app_support::folderSetOptions(), log);
    exports = own_export ? &*own_export : &out;
  }
  void commit() {
    if (own_export) own_export->commit();
    out.commit();
  }
};

/// One run of the app, step by step (IcpSlamApp::run() calls them in order).
class IcpSlamJob {
 public:
  IcpSlamJob(const IcpSlamAppParams& params, std::ostream& log) : params_(params), log_(log) {}

  /// Both configuration files, then the input: everything is checked before any output.
  void readInputs() {
    loadIcpIni(params_.icp_ini, ini_);
    slice_ = app_support::loadScanSliceParams(params_.icp_ini);
    std::vector<std::string> notices;  // keys given under their former names
    config_ = app_support::loadAppConfig(params_.freeinit_ini, &notices);
    for (const std::string& n : notices) log_ << n << "\n";
    log_ << "Reading " << params_.rawlog << "\n";
    in_ = app_support::readRecording(params_.rawlog, config_);
    for (const auto& w : in_.warnings) log_ << "Warning: " << w << "\n";
    if (config_.extrinsics.from_sensor_pose && in_.sensor_pose_extrinsics)
      config_.core.extrinsics = *in_.sensor_pose_extrinsics;
    if (const std::string tf = app_support::truthPathFor(params_.rawlog);
        std::filesystem::is_regular_file(tf))
      truth_ = app_support::readTruthCsv(tf);
  }

  /// Free-Init: the seed and the levelling of the scans. Without a state only the plain mode
  /// runs; returns 3 if a seeded mode was asked for then, else 0.
  int initialize(InitResult& freeinit) {
    freeinit = FreeInit::run(config_.core, in_.imu, in_.frames);
    state_ = freeinit.state;
    log_ << "Free-Init: " << toString(state_.status)
         << (state_.message.empty() ? "" : " (" + state_.message + ")") << "\n";
    modes_ = params_.modes;
    int rc = 0;
    if (!state_.ok()) {
      const auto n = modes_.size();
      modes_.erase(std::remove_if(modes_.begin(), modes_.end(),
                                  [](app_support::IcpSeedMode m) {
                                    return m != app_support::IcpSeedMode::Plain;
                                  }),
                   modes_.end());
      if (modes_.size() != n) {
        log_ << "Seeded runs skipped: no initial state\n";
        rc = 3;
      }
    }
    if (state_.ok()) seed_ = app_support::makeIcpSeed(freeinit, slice_);
    return rc;
  }

  /// The levelled scans, and the odometry with its deskewed scans when the odometry mode runs.
  void prepareScans() {
    const Mat3 R_level =
        state_.ok() ? app_support::levellingRotation(state_.q_wb) : Mat3::Identity();
    const Extrinsics& ext = config_.core.extrinsics;
    for (const auto& f : in_.frames)
      scans_.push_back(app_support::scanFromFrame(f, ext, R_level, slice_, "LIDAR"));
    if (std::count(modes_.begin(), modes_.end(), app_support::IcpSeedMode::Odometry) > 0) {
      odometry_ = DopplerInertialOdometry(config_.core, state_).run(in_.imu, in_.frames);
      log_ << "Doppler-inertial odometry: " << odometry_.size() << " poses, "
           << std::setprecision(4) << (odometry_.back().p_w - odometry_.front().p_w).norm()
           << " m travelled\n";
    }
    // The odometry mode's scans: deskewed with the odometry (frames it covers) when configured.
    odometry_scans_ = scans_;
    if (!odometry_.empty() && slice_.deskew_with_odometry) {
      for (std::size_t k = 0; k < in_.frames.size(); ++k)
        odometry_scans_[k] =
            app_support::scanFromFrame(in_.frames[k], ext, R_level, slice_, "LIDAR", &odometry_);
    }
  }

  /// The odometry alone, at the scans after the state time: the reference the fed run starts
  /// from (no map, no loop: its drift grows with the integrated velocity error).
  std::optional<app_support::PathErrors> writeOdometryAlone(app_support::OutputSet& set) {
    if (odometry_.empty() || truth_.empty()) return std::nullopt;
    std::vector<app_support::PlanarPathSample> path;
    for (const auto& sc : scans_) {
      const double t = mrpt_plugins::toUnix(sc->timestamp);
      if (t <= state_.timestamp || t > odometry_.back().t) continue;
      const app_support::BodyPose b = app_support::bodyPoseAt(odometry_, t);
      path.push_back({t, app_support::planarPose(b.q_wb, b.p_w)});
    }
    set.write(kOdometryAloneFile, [&](const std::string& p) { writeTumPlanar(p, path); });
    const app_support::PathErrors e =
        app_support::comparePathWithTruth(path, truth_, state_.timestamp);
    log_ << std::fixed << std::setprecision(3) << "  odometry alone: ATE " << e.ate_rmse
         << " m, end-point " << e.end_point << " m\n"
         << std::defaultfloat;
    return e;
  }

  /// Logs the seed and decides how it enters icp-slam, then writes it.
  ///
  /// How the seed enters (MRPT 2.5.8; docs/icp_slam.md, "What MRPT 2.5.8 does with the seed"):
  /// the map through initialize(); the pose through the first odometry reading, in w, as the
  /// stock app on the export gets it. initialize()'s pose argument is used only when a lone
  /// reading would block ICP (seeded mode, slow start): it keeps the mean only and stamps it with
  /// the wall clock, which hides later odometry from the pose estimator until the first ICP
  /// correction.
  void placeSeed(app_support::OutputSet& set) {
    if (!seed_) return;
    const auto& m = seed_->pose.mean;
    log_ << std::fixed << std::setprecision(3) << "Seed: pose (" << m.x() << ", " << m.y() << ", "
         << m.phi() * 180 / M_PI << " deg), sigma (" << std::sqrt(seed_->pose.cov(0, 0)) << " m, "
         << std::sqrt(seed_->pose.cov(1, 1)) << " m, "
         << std::sqrt(seed_->pose.cov(2, 2)) * 180 / M_PI << " deg), velocity ("
         << seed_->velocity_local.vx << ", " << seed_->velocity_local.vy << ") m/s\n"
         << std::defaultfloat;
    mrpt::slam::CMetricMapBuilderICP probe;
    probe.ICP_options.loadFromConfigFile(ini_.ini, kMappingSection);
    seed_reading_ = !seedReadingBlocksIcp(*seed_, probe.ICP_options);
    if (!seed_reading_ &&
        std::count(modes_.begin(), modes_.end(), app_support::IcpSeedMode::Seeded) > 0)
      log_ << "Seeded: the seed pose is closer to the window start than icp-slam's "
              "localization/insertion distances: it goes in as initialize()'s pose prior, "
              "without the velocity (a lone odometry reading would stop ICP)\n";
    set.write(kSeedIniFile, [&](const std::string& p) { writeSeedIni(p, *seed_); });
  }

  /// One icp-slam run per mode; outputs as the stock app names them, in <out>/<mode>/.
  std::vector<IcpSlamRun> runModes(app_support::OutputSet& set) {
    std::vector<IcpSlamRun> runs;
    for (const app_support::IcpSeedMode mode : modes_) {
      const app_support::IcpSeed* sd = seedFor(mode);
      const auto obs = icpSlamObservations(mode, scansFor(mode), sd, odometry_, seed_reading_);
      const bool prior = mode == app_support::IcpSeedMode::Seeded && !seed_reading_;
      BuilderOutput b = runBuilder(ini_.ini, sd, prior ? &sd->pose : nullptr, obs);
      IcpSlamRun r;
      r.mode = mode;
      r.path = std::move(b.path);
      r.keyframes = b.map.size();
      r.map_x = std::move(b.map_x);
      r.map_y = std::move(b.map_y);
      const std::string dir = std::string(toString(mode)) + "/";
      set.write(dir + kMapFile,
                [&](const std::string& p) { app_support::saveSimplemapAtomically(p, b.map); });
      set.write(dir + kStepLogFile, [&](const std::string& p) {
        writeFileAtomically(p, [&](std::ostream& o) { o << b.step_log; });
      });
      set.write(dir + kPathFile, [&](const std::string& p) { writeTumPlanar(p, r.path); });
      log_ << "icp-slam " << std::left << std::setw(9) << toString(mode) << std::right << ": "
           << r.path.size() << " scans, " << r.keyframes << " keyframes";
      if (!truth_.empty() && state_.ok()) {
        // Compared from the state time on: the span every mode covers.
        r.errors = app_support::comparePathWithTruth(r.path, truth_, state_.timestamp);
        const app_support::PathErrors& e = *r.errors;
        log_ << std::fixed << std::setprecision(3) << ", ATE " << e.ate_rmse << " m, end-point "
             << e.end_point << " m over " << e.length << " m" << std::defaultfloat;
        set.write(dir + kErrorsFile, [&](const std::string& p) {
          writeFileAtomically(p, [&](std::ostream& o) {
            o << "; icp-slam path vs ground truth, poses at the scans from the Free-Init state "
                 "time,\n; after the best SE(2) alignment\n[errors_wrt_gt]\nmode = "
              << toString(mode) << "\nsamples = " << e.samples << "\nate_rmse = " << e.ate_rmse
              << "   ; [m]\nend_point = " << e.end_point << "   ; [m]\ntrue_length = " << e.length
              << "   ; [m]\n";
          });
        });
      }
      log_ << "\n";
      runs.push_back(std::move(r));
    }
    return runs;
  }

  /// The export for the stock icp-slam app: one observations-only rawlog of stock classes per
  /// mode (no IMU, no plugin class) and a matching INI. The stock app has no initial-map option:
  /// the static map is the first observation (inserted at the origin of the still empty map),
  /// followed by the same observations as above (the seed pose as an odometry reading in w). It
  /// cannot take a pose prior: in the seeded mode of a slow start it starts at w's origin,
  /// within icp-slam's localization distance of the seed pose.
  void writeExport(app_support::OutputSet& set) {
    // The INI names the files where they will be once installed.
    const std::filesystem::path ex = std::filesystem::absolute(params_.export_dir);
    for (const app_support::IcpSeedMode mode : modes_) {
      const app_support::IcpSeed* sd = seedFor(mode);
      std::vector<mrpt::obs::CObservation::Ptr> obs;
      if (sd) obs.push_back(sd->map_observation);
      const auto rest = icpSlamObservations(mode, scansFor(mode), sd, odometry_, seed_reading_);
      obs.insert(obs.end(), rest.begin(), rest.end());
      const std::string name = toString(mode);
      const std::string rawlog = (ex / (name + ".rawlog")).string();
      set.write(name + ".rawlog",
                [&](const std::string& p) { app_support::writeObservationRawlog(p, obs); });
      mrpt::config::CConfigFileMemory cfg(ini_.text);
      cfg.write(kMappingSection, "rawlog_file", rawlog);
      cfg.write(kMappingSection, "logOutput_dir", (ex / (name + "_icp_slam_out")).string());
      std::string text;
      cfg.getContent(text);
      set.write(name + ".ini", [&](const std::string& p) {
        writeFileAtomically(p, [&](std::ostream& o) {
          o << "; icp-slam " << name << ".ini   (from " << params_.icp_ini << " for " << rawlog
            << ")\n"
            << text;
        });
      });
      log_ << "Export: icp-slam " << (ex / (name + ".ini")).string() << "\n";
    }
  }

  /// The results table (when the truth is present) and the picture of maps and paths.
  void writeSummary(app_support::OutputSet& set, const std::vector<IcpSlamRun>& runs,
                    const std::optional<app_support::PathErrors>& odometry_errors) {
    if (!runs.empty() && runs.front().errors) {
      set.write(kResultsFile, [&](const std::string& p) {
        writeFileAtomically(p, [&](std::ostream& o) {
          o << "# mode ate_rmse[m] end_point[m] true_length[m] scans keyframes\n" << std::fixed;
          if (odometry_errors)
            o << "odometry_alone " << std::setprecision(3) << odometry_errors->ate_rmse << " "
              << odometry_errors->end_point << " " << odometry_errors->length << " "
              << odometry_errors->samples << " 0\n";
          for (const auto& r : runs)
            o << toString(r.mode) << " " << std::setprecision(3) << r.errors->ate_rmse << " "
              << r.errors->end_point << " " << r.errors->length << " " << r.path.size() << " "
              << r.keyframes << "\n";
        });
      });
    }
    if (params_.snapshot && !runs.empty()) {
      set.write(kPictureFile, [&](const std::string& p) {
        renderRuns(p, std::filesystem::path(params_.rawlog).filename().string(), runs, truth_,
                   state_.timestamp, params_.snapshot_width, params_.snapshot_height);
      });
      log_ << "Picture: " << set.finalPath(kPictureFile) << "\n";
    }
  }

 private:
  const app_support::IcpSeed* seedFor(app_support::IcpSeedMode m) const {
    return m == app_support::IcpSeedMode::Plain ? nullptr : &*seed_;
  }
  const std::vector<mrpt::obs::CObservation2DRangeScan::Ptr>& scansFor(
      app_support::IcpSeedMode m) const {
    return m == app_support::IcpSeedMode::Odometry ? odometry_scans_ : scans_;
  }

  const IcpSlamAppParams& params_;
  std::ostream& log_;
  IcpIni ini_;
  app_support::ScanSliceParams slice_;
  app_support::AppConfig config_;
  app_support::CheckedRecording in_;
  std::vector<app_support::TruthSample> truth_;
  InitialState state_;
  std::vector<app_support::IcpSeedMode> modes_;
  std::optional<app_support::IcpSeed> seed_;
  bool seed_reading_ = true;  ///< the seed pose goes in as an odometry reading
  std::vector<mrpt::obs::CObservation2DRangeScan::Ptr> scans_, odometry_scans_;
  std::vector<OdometrySample> odometry_;
};

}  // namespace

int IcpSlamApp::run(std::ostream& log) {
  IcpOutputs outputs(params, log);
  IcpSlamJob job(params, log);
  job.readInputs();
  const int rc = job.initialize(freeinit);
  job.prepareScans();
  odometry_errors = job.writeOdometryAlone(outputs.out);
  job.placeSeed(outputs.out);
  runs = job.runModes(outputs.out);
  if (outputs.exports) job.writeExport(*outputs.exports);
  job.writeSummary(outputs.out, runs, odometry_errors);
  outputs.commit();
  return rc;
}

int IcpSlamApp::main(int argc, char** argv) {
  app_support::CommandLine cli("freeinit-icp-slam",
                               "MRPT icp-slam (CMetricMapBuilderICP) started plain, seeded by "
                               "Free-Init's static map, pose and velocity, or seeded and fed with "
                               "Doppler-inertial odometry");
  const auto& icp_ini =
      cli.positional("icp_slam.ini", "icp-slam INI ([MappingApplication], [ICP], [freeinit_scan])");
  const auto& fi_ini = cli.positional("freeinit.ini", "Free-Init INI");
  const auto& rawlog = cli.positional("input.rawlog", "input rawlog");
  const auto& mode =
      cli.choice("m", "mode", "icp-slam start", "all", {"plain", "seeded", "odometry", "all"});
  const auto& out = cli.text("o", "out", "output folder", "icp_slam_out", "DIR");
  const auto& exp = cli.text("e", "export",
                             "also write <DIR>/<mode>.rawlog + <mode>.ini for the stock icp-slam "
                             "app",
                             "", "DIR", "none");
  const auto& no_png = cli.flag("", "no-png", "do not render trajectories.png");
  if (const auto code = cli.parse(argc, argv)) return *code;
  return app_support::runMain(cli.program(), [&] {
    IcpSlamApp app;
    app.params.icp_ini = icp_ini.value;
    app.params.freeinit_ini = fi_ini.value;
    app.params.rawlog = rawlog.value;
    app.params.out_dir = out.value;
    app.params.export_dir = exp.value;
    app.params.snapshot = !no_png.value;
    if (mode.value != "all") app.params.modes = {app_support::seedModeFromString(mode.value)};
    return app.run(std::cout);
  });
}

}  // namespace freeinit::apps
