#include "sim_app.h"

#include <freeinit/app_support/command_line.h>
#include <freeinit/app_support/ground_truth.h>
#include <freeinit/app_support/output_set.h>
#include <freeinit/app_support/output_writers.h>
#include <freeinit/app_support/progress_bar.h>
#include <freeinit/app_support/stop_signal.h>
#include <freeinit/mrpt_plugins/rawlog_writer.h>
#include <freeinit/mrpt_plugins/register.h>
#include <freeinit/sim/random_scenario.h>
#include <freeinit/sim/scenario_ini.h>
#include <freeinit/sim/simulator.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <system_error>

namespace freeinit::apps {
namespace {

// The [scenario] section of `file` over its base (sim/scenario_ini.h), read strictly: unknown
// sections and keys, keys given twice and bad values are errors naming the file, line and key.
sim::ScenarioConfig loadScenario(const std::string& file, const SimAppParams& p) {
  return sim::loadScenarioIni(file, {p.preset, p.seed});
}

bool sameExtrinsics(const Extrinsics& a, const Extrinsics& b) {
  return a.R_bl == b.R_bl && a.p_bl == b.p_bl;
}

/// What a scenario costs before it is simulated: the rawlog's bytes before compression (a
/// return's seven fields take 25 bytes, and Doppler data hardly compress) and the memory that
/// holds the recording while it is written (the simulator keeps every frame).
struct SimulationSize {
  std::size_t frames = 0, imu_samples = 0;
  double rawlog_bytes = 0, memory_bytes = 0;
};

SimulationSize sizeOf(const sim::ScenarioConfig& sc) {
  SimulationSize z;
  z.frames = sim::frameCount(sc);
  z.imu_samples = static_cast<std::size_t>(sc.duration * sc.imu_rate) + 1;
  const double points = static_cast<double>(z.frames) * static_cast<double>(sc.points_per_frame);
  z.rawlog_bytes = points * 25.0 + static_cast<double>(z.frames) * 400.0 +
                   static_cast<double>(z.imu_samples) * 300.0;
  z.memory_bytes = points * static_cast<double>(sizeof(DopplerPoint) + 1);
  return z;
}

std::string gigabytes(double bytes) {
  std::ostringstream os;
  if (bytes >= 1e9)
    os << std::fixed << std::setprecision(1) << bytes / 1e9 << " GB";
  else
    os << std::fixed << std::setprecision(bytes >= 1e7 ? 0 : 1) << bytes / 1e6 << " MB";
  return os.str();
}

/// Progress of the long runs only (a short one prints what it always printed).
constexpr double kProgressFromBytes = 200e6;

}  // namespace

std::string SimApp::scenarioKeys() { return sim::scenarioKeysHelp(); }

void SimApp::run(std::ostream& log) {
  mrpt_plugins::registerClasses();
  if (params.random && !params.scenario_file.empty())
    throw std::invalid_argument("a random scenario and a scenario file cannot both be given");
  // The recording and its truth files are one set (output_set.h), named after the rawlog.
  const std::string out = params.output;
  const std::string stem = mrpt_plugins::rawlogStem(out);
  const std::filesystem::path stem_path(stem);
  const std::string base = stem_path.filename().string();
  const std::string rawlog_name = std::filesystem::path(out).filename().string();
  if (base.empty() || rawlog_name.empty())
    throw std::invalid_argument(out + ": the output must name a file");
  app_support::OutputSetOptions set_options;
  set_options.owned = {rawlog_name,
                       base + ".truth.csv",
                       base + ".truth_tum.txt",
                       base + ".extrinsics.ini",
                       base + ".truth_extrinsics.ini",
                       base + ".scenario.ini"};
  set_options.install_last = {rawlog_name};
  app_support::OutputSet set(stem_path.parent_path().string(), base, set_options, log);
  sim::ScenarioConfig sc;
  sim::RandomScenarioInfo info;  // what a random scenario drew
  if (params.random) {
    const sim::RandomScenario r = sim::drawRandomScenario(params.seed);
    sc = r.config;
    info = r.info;
  } else if (!params.scenario_file.empty()) {
    sc = loadScenario(params.scenario_file, params);
  } else {
    sc = sim::preset(params.preset, params.seed);
  }
  if (params.duration > 0) sc.duration = params.duration;
  if (params.points_per_frame > 0) sc.points_per_frame = params.points_per_frame;
  // What it will take, checked before any work: the disk the rawlog goes to and the memory that
  // holds the recording.
  const SimulationSize size = sizeOf(sc);
  std::ostringstream what;
  what << "-d " << sc.duration << " -n " << sc.points_per_frame << ": " << size.frames
       << " point clouds of " << sc.points_per_frame << " points, about "
       << gigabytes(size.rawlog_bytes) << " of rawlog";
  std::error_code ec;
  const std::filesystem::path folder =
      std::filesystem::absolute(stem_path.parent_path().empty() ? "." : stem_path.parent_path());
  std::filesystem::path probe = folder;  // the nearest folder that exists (the set creates it)
  while (!probe.empty() && !std::filesystem::exists(probe, ec) && probe != probe.root_path())
    probe = probe.parent_path();
  const std::filesystem::space_info disk = std::filesystem::space(probe, ec);
  if (!ec && size.rawlog_bytes > static_cast<double>(disk.available))
    throw std::invalid_argument(what.str() + ", more than the " +
                                gigabytes(static_cast<double>(disk.available)) + " free on " +
                                probe.string() + " (-d is in seconds)");
  const double physical =
      static_cast<double>(sysconf(_SC_PHYS_PAGES)) * static_cast<double>(sysconf(_SC_PAGE_SIZE));
  if (physical > 0 && size.memory_bytes > 0.8 * physical)
    throw std::invalid_argument(what.str() + "; simulating it holds about " +
                                gigabytes(size.memory_bytes) + " in memory, more than this " +
                                gigabytes(physical) + " machine has (-d is in seconds)");
  const bool large = size.rawlog_bytes >= kProgressFromBytes;
  log << "Simulating " << (sc.name == "random" ? "random scenario " : "preset ")
      << (sc.name == "random" ? std::to_string(sc.seed) : sc.name) << " (seed " << sc.seed << ", "
      << sc.duration << " s, " << sc.points_per_frame << " points/frame, IMU " << sc.imu_rate
      << " Hz" << (large ? "; about " + gigabytes(size.rawlog_bytes) + " to write" : "")
      << ")...\n";
  const bool terminal = isatty(STDOUT_FILENO) != 0;
  app_support::ProgressBar simulating(log, "  simulating", "frames", terminal);
  const sim::Recording rec = sim::simulate(sc, [&](std::size_t done, std::size_t total) {
    app_support::throwIfStopRequested();
    if (large) simulating.update(done, total);
  });
  if (large) simulating.finish();
  app_support::throwIfStopRequested();
  std::vector<std::string> drawn;
  if (params.random) {
    sim::measureMovingPoints(info, rec);
    drawn = sim::describe(info);
  }
  for (const auto& line : drawn) log << "  " << line << "\n";

  const bool declared_true = sameExtrinsics(rec.declared_extrinsics, rec.extrinsics);

  // The rawlog: observations only, merged by timestamp (IMU first on ties).
  const double g_scale = params.accel_in_g ? 1.0 / kGravity : 1.0;
  // It carries what a user would declare (possibly wrong), and the LiDAR stamps on their clock.
  set.write(rawlog_name, [&](const std::string& path) {
    mrpt_plugins::RawlogWriter rawlog(path, rec.declared_extrinsics, params.imu_label,
                                      params.lidar_label);
    app_support::ProgressBar writing(log, "  writing", "records", terminal);
    const std::size_t total = rec.imu.size() + rec.frames.size();
    std::size_t i = 0, k = 0;
    while (i < rec.imu.size() || k < rec.frames.size()) {
      if ((i + k) % 512 == 0) app_support::throwIfStopRequested();
      if (large) writing.update(i + k, total);
      const bool take_imu =
          k >= rec.frames.size() || (i < rec.imu.size() && rec.imu[i].t <= rec.frames[k].stamp);
      if (take_imu) {
        ImuSample s = rec.imu[i++];
        s.accel *= g_scale;
        rawlog.write(s);
      } else {
        rawlog.write(rec.frames[k++]);
      }
    }
    rawlog.commit();
    if (large) writing.finish();
    records_written = rawlog.records();
  });

  // Ground truth at every IMU sample.
  std::vector<app_support::TruthSample> truth;
  truth.reserve(rec.imu.size());
  for (const auto& s : rec.imu) {
    const sim::TruthState x = rec.truth(s.t);
    app_support::TruthSample t;
    t.t = s.t;
    t.q_wb = Quat(x.R_wb);
    t.p_w = x.p_w;
    t.v_w = x.v_w;
    t.omega_b = x.omega_b;
    t.b_g = rec.b_g;
    t.b_a = rec.b_a;
    t.g_w = rec.g_w;
    truth.push_back(t);
  }
  set.write(base + ".truth.csv",
            [&](const std::string& p) { app_support::writeTruthCsv(p, truth); });
  set.write(base + ".truth_tum.txt", [&](const std::string& p) {
    writeFileAtomically(p, [&](std::ostream& o) {
      o << "# ground truth: timestamp x y z qx qy qz qw (body = IMU frame, world z up)\n";
      for (const auto& t : truth)
        o << std::fixed << std::setprecision(9) << t.t << " " << t.p_w.x() << " " << t.p_w.y()
          << " " << t.p_w.z() << " " << t.q_wb.x() << " " << t.q_wb.y() << " " << t.q_wb.z() << " "
          << t.q_wb.w() << "\n";
    });
  });
  set.write(base + ".extrinsics.ini", [&](const std::string& p) {
    mrpt_plugins::writeExtrinsicsIni(
        p, rec.declared_extrinsics,
        declared_true ? "true extrinsics of " + out + " (also in each point cloud's sensorPose)"
                      : "declared (not the true) extrinsics of " + out +
                            " (also in each point cloud's sensorPose); the truth "
                            "is in " +
                            stem + ".truth_extrinsics.ini");
  });
  std::ostringstream clock;
  clock << std::setprecision(17) << rec.lidar_time_offset;
  set.write(base + ".truth_extrinsics.ini", [&](const std::string& p) {
    mrpt_plugins::writeExtrinsicsIni(p, rec.extrinsics,
                                     "true extrinsics of " + out +
                                         "; true LiDAR clock offset: LiDAR stamps = IMU time + " +
                                         clock.str() + " s");
  });
  std::vector<std::string> comments = {"scenario of " + out +
                                       ", written by freeinit-sim: `freeinit-sim -c " + stem +
                                       ".scenario.ini -o X.rawlog` simulates the same recording"};
  comments.insert(comments.end(), drawn.begin(), drawn.end());
  set.write(base + ".scenario.ini",
            [&](const std::string& p) { sim::writeScenarioIni(p, sc, comments); });
  set.commit();
  log << "Wrote " << out << " (" << records_written << " records: " << rec.imu.size() << " IMU, "
      << rec.frames.size() << " point clouds), " << stem << ".truth.csv, " << stem
      << ".truth_tum.txt, " << stem << ".extrinsics.ini, " << stem << ".truth_extrinsics.ini, "
      << stem << ".scenario.ini\n";
  if (!declared_true || rec.lidar_time_offset != 0)
    log << "The declared calibration is wrong on purpose (the truth: " << stem
        << ".truth_extrinsics.ini)\n";
  log << std::setprecision(6) << "True biases: b_g = " << rec.b_g.transpose()
      << " rad/s, b_a = " << rec.b_a.transpose() << " m/s^2\n";
}

int SimApp::main(int argc, char** argv) {
  namespace range = freeinit::config;
  app_support::CommandLine cli("freeinit-sim",
                               "Doppler LiDAR + IMU recording with ground truth, as a rawlog");
  const auto& preset =
      cli.choice("p", "preset", "simulator preset", "dyna_01", freeinit::sim::presetNames());
  const auto& seed = cli.integer("s", "seed", "random seed", 1, 0, 4294967295LL, "N");
  const auto& random = cli.integer("", "random",
                                   "simulate the randomized scenario drawn with this seed "
                                   "(instead of a preset)",
                                   0, 0, 4294967295LL, "SEED");
  const auto& duration =
      cli.number("d", "duration", "seconds (0: the preset's)", 0, range::between(0, 3600), "S");
  const auto& points = cli.integer("n", "points-per-frame", "points per frame (0: the preset's)", 0,
                                   0, 10000000, "N");
  const auto& out = cli.text("o", "out", "output rawlog; truth files go beside it", "", "FILE",
                             "<preset>.rawlog");
  const auto& scenario = cli.text("c", "scenario",
                                  "INI file with a [scenario] section (a base preset or random "
                                  "+ scenario keys, or a written <out>.scenario.ini)",
                                  "", "FILE", "none");
  const auto& keys = cli.flag("", "scenario-keys", "print the [scenario] keys and exit");
  const auto& in_g = cli.flag("", "accel-in-g", "write accelerations in g");
  if (const auto code = cli.parse(argc, argv)) return *code;
  return app_support::runMain(cli.program(), [&] {
    if (keys.value) {
      std::cout << SimApp::scenarioKeys();
      return 0;
    }
    if (random.given && (seed.given || preset.given || scenario.given))
      throw std::invalid_argument("--random: not with --seed, --preset or --scenario");
    SimApp app;
    app.params.preset = preset.value;
    app.params.seed = static_cast<std::uint64_t>(random.given ? random.value : seed.value);
    app.params.random = random.given;
    app.params.duration = duration.value;
    app.params.points_per_frame = static_cast<int>(points.value);
    const std::string base = random.given ? "random_" + std::to_string(random.value) : preset.value;
    app.params.output = out.given ? out.value : base + ".rawlog";
    app.params.accel_in_g = in_g.value;
    app.params.scenario_file = scenario.value;
    app.run(std::cout);
    return 0;
  });
}

}  // namespace freeinit::apps
