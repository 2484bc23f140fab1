#include <freeinit/mrpt/RawlogWriter.h>
#include <freeinit/mrpt/SimApp.h>
#include <freeinit/mrpt/ground_truth.h>
#include <freeinit/mrpt/output_writers.h>
#include <freeinit/mrpt/register.h>
#include <freeinit/sim/simulator.h>
#include <mrpt/config/CConfigFile.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <ostream>
#include <set>
#include <sstream>
#include <stdexcept>

namespace freeinit::mrpt_glue {
namespace {

// The [scenario] section of `file` over its base preset; every unknown key is an error.
sim::ScenarioConfig loadScenario(const std::string& file, const SimAppParams& p) {
  if (!std::filesystem::is_regular_file(file))
    throw std::invalid_argument(file + ": scenario file not found");
  mrpt::config::CConfigFile cfg(file);
  const std::string sec = "scenario";
  if (!cfg.sectionExists(sec)) throw std::invalid_argument(file + ": no [scenario] section");
  auto fail = [&](const std::string& key, const std::string& why) {
    throw std::invalid_argument(file + ": [" + sec + "] " + key + ": " + why);
  };
  const std::string base = cfg.read_string(sec, "preset", p.preset);
  const auto seed = static_cast<std::uint64_t>(cfg.read_uint64_t(sec, "seed", p.seed));
  sim::ScenarioConfig sc;
  try {
    sc = sim::preset(base, seed);
  } catch (const std::exception& e) {
    fail("preset", e.what());
  }
  std::set<std::string> known = {"preset", "seed"};
  auto num = [&](const char* key, double& x, double min_exclusive) {
    known.insert(key);
    if (!cfg.keyExists(sec, key)) return;
    x = cfg.read_double(sec, key, x);
    if (!std::isfinite(x) || !(x > min_exclusive))
      fail(key, "must be a number > " + std::to_string(min_exclusive));
  };
  auto integer = [&](const char* key, int& x) {
    known.insert(key);
    if (!cfg.keyExists(sec, key)) return;
    x = cfg.read_int(sec, key, x);
    if (x <= 0) fail(key, "must be > 0");
  };
  auto vec = [&](const char* key, Vec3& v) {
    known.insert(key);
    if (!cfg.keyExists(sec, key)) return false;
    std::istringstream is(cfg.read_string(sec, key, ""));
    std::string rest;
    if (!(is >> v.x() >> v.y() >> v.z()) || (is >> rest) || !v.allFinite())
      fail(key, "expected three numbers \"x y z\"");
    return true;
  };
  num("t0", sc.t0, 0);
  num("duration", sc.duration, 0);
  integer("points_per_frame", sc.points_per_frame);
  integer("lines", sc.lines);
  num("frame_rate", sc.frame_rate, 0);
  num("hfov_deg", sc.hfov_deg, 0);
  num("vfov_deg", sc.vfov_deg, 0);
  num("min_range", sc.min_range, 0);
  num("max_range", sc.max_range, sc.min_range);
  num("range_sigma", sc.range_sigma, -1e-300);
  num("doppler_sigma", sc.doppler_sigma, -1e-300);
  num("outlier_ratio", sc.outlier_ratio, -1e-300);
  if (sc.outlier_ratio > 1) fail("outlier_ratio", "must be in [0, 1]");
  num("imu_rate", sc.imu_rate, 0);
  num("gyro_sigma", sc.gyro_sigma, -1e-300);
  num("accel_sigma", sc.accel_sigma, -1e-300);
  const bool biases_given = vec("b_g", sc.b_g) | vec("b_a", sc.b_a);
  known.insert("random_biases");
  sc.random_biases = cfg.read_bool(sec, "random_biases", !biases_given);
  std::vector<std::string> keys;
  cfg.getAllKeys(sec, keys);
  for (const auto& k : keys)
    if (!known.count(k)) fail(k, "unknown key");
  return sc;
}

}  // namespace

void SimApp::run(std::ostream& log) {
  registerClasses();
  sim::ScenarioConfig sc = params.scenario_file.empty()
                               ? sim::preset(params.preset, params.seed)
                               : loadScenario(params.scenario_file, params);
  if (params.duration > 0) sc.duration = params.duration;
  if (params.points_per_frame > 0) sc.points_per_frame = params.points_per_frame;
  log << "Simulating preset " << sc.name << " (seed " << sc.seed << ", " << sc.duration << " s, "
      << sc.points_per_frame << " points/frame, IMU " << sc.imu_rate << " Hz)...\n";
  const sim::Recording rec = sim::simulate(sc);

  const std::string out = params.output;
  const std::string stem = rawlogStem(out);

  // The rawlog: observations only, merged by timestamp (IMU first on ties).
  const double g_scale = params.accel_in_g ? 1.0 / kGravity : 1.0;
  RawlogWriter rawlog(out, rec.extrinsics, params.imu_label, params.lidar_label);
  std::size_t i = 0, k = 0;
  while (i < rec.imu.size() || k < rec.frames.size()) {
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
  records_written = rawlog.records();

  // Ground truth at every IMU sample.
  std::vector<TruthSample> truth;
  truth.reserve(rec.imu.size());
  for (const auto& s : rec.imu) {
    const sim::TruthState x = rec.truth(s.t);
    TruthSample t;
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
  writeTruthCsv(stem + ".truth.csv", truth);
  writeFileAtomically(stem + ".truth_tum.txt", [&](std::ostream& o) {
    o << "# ground truth: timestamp x y z qx qy qz qw (body = IMU frame, world z up)\n";
    for (const auto& t : truth)
      o << std::fixed << std::setprecision(9) << t.t << " " << t.p_w.x() << " " << t.p_w.y() << " "
        << t.p_w.z() << " " << t.q_wb.x() << " " << t.q_wb.y() << " " << t.q_wb.z() << " "
        << t.q_wb.w() << "\n";
  });
  writeExtrinsicsIni(stem + ".extrinsics.ini", rec.extrinsics,
                     "true extrinsics of " + out + " (also in each point cloud's sensorPose)");
  log << "Wrote " << out << " (" << records_written << " records: " << rec.imu.size() << " IMU, "
      << rec.frames.size() << " point clouds), " << stem << ".truth.csv, " << stem
      << ".truth_tum.txt, " << stem << ".extrinsics.ini\n";
  log << std::setprecision(6) << "True biases: b_g = " << rec.b_g.transpose()
      << " rad/s, b_a = " << rec.b_a.transpose() << " m/s^2\n";
}

}  // namespace freeinit::mrpt_glue
