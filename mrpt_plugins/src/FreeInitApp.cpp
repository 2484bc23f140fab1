#include <freeinit/mrpt/FreeInitApp.h>
#include <freeinit/mrpt/FreeInitObservationHandler.h>
#include <freeinit/mrpt/ProgressBar.h>
#include <freeinit/mrpt/input_validator.h>
#include <freeinit/mrpt/map_export.h>
#include <freeinit/mrpt/output_writers.h>
#include <freeinit/mrpt/rawlog_reader.h>
#include <freeinit/mrpt/snapshots.h>

#include <chrono>
#include <filesystem>
#include <iomanip>
#include <ostream>
#include <sstream>

namespace freeinit::mrpt_glue {
namespace {

std::string v3(const Vec3& v) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(4) << v.x() << " " << v.y() << " " << v.z();
  return os.str();
}

constexpr const char* kSimplemapFile = "static_map.simplemap";
constexpr const char* kPlyFile = "static_map.ply";
constexpr const char* kTrajectoryFile = "trajectory_tum.txt";
constexpr const char* kVelocityCsvFile = "velocimeter.csv";
constexpr const char* kMapPngFile = "static_map.png";
constexpr const char* kVelocityPngFile = "velocity.png";

}  // namespace

std::vector<std::string> resultFileNames() {
  return {kSimplemapFile,   kPlyFile,    kTrajectoryFile,
          kVelocityCsvFile, kMapPngFile, kVelocityPngFile};
}

void writeResultFiles(const std::string& out_dir, const OutputParams& output,
                      const InitResult& result, const std::vector<TruthSample>& truth) {
  const std::filesystem::path out(out_dir);
  auto file = [&](const char* name) { return (out / name).string(); };
  if (output.simplemap) writeStaticSimplemap(file(kSimplemapFile), result);
  if (output.ply) writePly(file(kPlyFile), result.static_map);
  if (output.trajectory) writeTum(file(kTrajectoryFile), result.trajectory);
  if (output.velocities) writeVelocityCsv(file(kVelocityCsvFile), result.velocities);
  if (output.snapshots) {
    if (!result.static_map.empty())
      renderMapSnapshot(file(kMapPngFile), result, output.snapshot_width, output.snapshot_height);
    if (!result.velocities.empty())
      renderVelocityPlot(file(kVelocityPngFile), result, truth, output.snapshot_width,
                         output.snapshot_height);
  }
}

int FreeInitApp::run(std::ostream& log) {
  using Clock = std::chrono::steady_clock;
  const auto t_start = Clock::now();

  // 1. Configuration, echoed.
  config = loadAppConfig(params.config_file);
  std::ostringstream effective;
  dumpAppConfig(config, effective);
  log << "Effective configuration (" << params.config_file << "):\n" << effective.str() << "\n";

  // 2. Input: read everything, then validate. Any problem throws before an output exists.
  log << "Reading " << params.rawlog << "\n";
  std::vector<RawlogRecord> records;
  if (params.progress) {
    ProgressBar inflate(log, "  inflating", "MB", params.progress_terminal, 1e6);
    ProgressBar parse(log, "  parsing", "MB", params.progress_terminal, 1e6);
    RawlogReadProgress cb;
    cb.inflate = [&](std::size_t d, std::size_t t) { inflate.update(d, t); };
    cb.parse = [&](std::size_t d, std::size_t t) {
      inflate.finish();
      parse.update(d, t);
    };
    records = readRawlog(params.rawlog, cb);
    parse.finish(std::to_string(records.size()) + " observations");
  } else {
    records = readRawlog(params.rawlog);
  }
  const ValidatedInput in = validateInput(records, config, params.rawlog);
  for (const auto& w : in.warnings) log << "Warning: " << w << "\n";
  if (in.invalid_points_dropped > 0)
    log << "Warning: dropped " << in.invalid_points_dropped << " NaN/inf points\n";
  log << "Input: " << records.size() << " observations, " << in.imu.size() << " IMU samples ("
      << std::fixed << std::setprecision(3) << in.imu.front().t << " .. " << in.imu.back().t
      << "), " << in.frames.size() << " point clouds\n"
      << std::defaultfloat;
  if (config.extrinsics.from_sensor_pose && in.sensor_pose_extrinsics)
    log << "Extrinsics from sensorPose: p_bl = " << v3(in.sensor_pose_extrinsics->p_bl) << " m\n";

  // 3. Run the estimator over the observations in file order.
  FreeInitObservationHandler handler(config);
  const std::size_t total = records.size();
  std::size_t done = 0;
  log << "Estimating\n";
  ProgressBar bar(log, "  running", "observations", params.progress_terminal);
  for (const auto& r : records) {
    try {
      handler.process(r.obs);
    } catch (const std::exception& e) {
      throw InputError(params.rawlog + ": record " + std::to_string(r.index) + ": " + e.what());
    }
    ++done;
    if (params.progress) bar.update(done, total);
    if (handler.ready()) break;
  }
  const bool early = handler.ready() && done < total;
  if (!handler.ready()) handler.finish();
  if (params.progress)
    bar.finish(early ? "(state ready: the rest of the input is not needed)" : "");
  result = handler.result();
  const InitialState& s = result.state;

  log << "Initialization: " << toString(s.status)
      << (s.message.empty() ? "" : " (" + s.message + ")") << "\n";
  log << std::fixed << std::setprecision(6) << "  timestamp " << s.timestamp << "\n"
      << std::setprecision(4) << "  v_b  " << v3(s.v_b()) << " m/s\n  g_b  " << v3(s.g_b())
      << " m/s^2\n  b_g  " << v3(s.b_g) << " rad/s\n  b_a  " << v3(s.b_a) << " m/s^2\n"
      << std::defaultfloat << "  points: " << result.diag.points_used << " used, "
      << result.diag.points_rejected << " rejected, " << result.diag.points_skipped
      << " skipped; static start: " << (result.diag.static_start ? "yes" : "no") << "\n";

  // 4. Ground truth, when it sits beside the rawlog.
  errors_wrt_gt.reset();
  std::vector<TruthSample> truth;
  const std::string truth_file = truthPathFor(params.rawlog);
  if (std::filesystem::is_regular_file(truth_file)) {
    truth = readTruthCsv(truth_file);
    if (s.ok()) {
      errors_wrt_gt = compareWithTruth(s, truth);
      log << "Errors w.r.t. ground truth (" << truth_file << "):\n"
          << "  velocity    " << errors_wrt_gt->velocity << " m/s\n"
          << "  gravity     " << errors_wrt_gt->gravity_deg << " deg\n"
          << "  gyro bias   " << errors_wrt_gt->gyro_bias << " rad/s\n"
          << "  accel bias  " << errors_wrt_gt->accel_bias << " m/s^2\n";
    }
  }

  // 5. Outputs, each written atomically.
  const std::filesystem::path out(params.out_dir);
  std::filesystem::create_directories(out);
  auto file = [&](const char* name) { return (out / name).string(); };
  writeFileAtomically(file("effective_config.ini"), [&](std::ostream& o) { o << effective.str(); });
  writeInitialStateIni(file("initial_state.ini"), s);
  if (errors_wrt_gt) writeTruthErrors(file("errors_wrt_gt.ini"), *errors_wrt_gt);
  writeResultFiles(params.out_dir, config.output, result, truth);
  const double secs = std::chrono::duration<double>(Clock::now() - t_start).count();
  log << "Outputs in " << out.string() << " (" << std::setprecision(3) << secs << " s total)\n";
  return s.ok() ? 0 : 3;
}

}  // namespace freeinit::mrpt_glue
