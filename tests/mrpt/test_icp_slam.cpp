// MRPT icp-slam started plain, seeded by Free-Init, and fed with Doppler-inertial odometry, on
// moving starts of the wheeled and vehicular presets (street and tunnel), against the simulator's
// ground truth; and the export that the stock icp-slam app runs on.
#include <freeinit/mrpt_plugins/conversions.h>
#include <freeinit/mrpt_plugins/rawlog_reader.h>
#include <gtest/gtest.h>
#include <mrpt/maps/CSimpleMap.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "icp_slam_app.h"
#include "sim_app.h"

using namespace freeinit;
using namespace freeinit::mrpt_plugins;
using namespace freeinit::app_support;
using namespace freeinit::apps;
namespace fs = std::filesystem;

namespace {
const std::string kSrc = FREEINIT_SOURCE_DIR;

/// One folder per process (ctest runs each test in its own process, maybe in parallel), removed
/// when the process ends.
const fs::path& processDir() {
  struct Dir {
    fs::path path =
        fs::temp_directory_path() / "freeinit_icp_slam_tests" / std::to_string(::getpid());
    ~Dir() {
      std::error_code ec;
      fs::remove_all(path, ec);
    }
  };
  static const Dir dir;
  return dir.path;
}

fs::path testDir(const std::string& name) {
  const auto d = processDir() / name;
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

struct PresetRun {
  IcpSlamApp app;
  std::string log;
  int rc = -1;
};

/// 3 s (default) at 20,000 points per frame: 25 scans after the 0.5 s window, 20-60 m of driving.
const PresetRun& run(const std::string& preset, double duration = 3.0) {
  static std::map<std::string, PresetRun> cache;
  auto it = cache.find(preset);
  if (it != cache.end()) return it->second;
  const fs::path dir = testDir(preset);
  SimApp sim;
  sim.params.preset = preset;
  sim.params.duration = duration;
  sim.params.points_per_frame = 20000;
  sim.params.output = (dir / (preset + ".rawlog")).string();
  std::ostringstream sim_log;
  sim.run(sim_log);
  PresetRun& r = cache[preset];
  r.app.params.icp_ini = kSrc + "/ini/icp_slam.ini";
  r.app.params.freeinit_ini = kSrc + "/ini/freeinit.ini";
  r.app.params.rawlog = sim.params.output;
  r.app.params.out_dir = (dir / "out").string();
  r.app.params.export_dir = (dir / "export").string();
  std::ostringstream log;
  r.rc = r.app.run(log);
  r.log = log.str();
  return r;
}

const IcpSlamRun& byMode(const IcpSlamApp& app, IcpSeedMode m) {
  for (const auto& r : app.runs)
    if (r.mode == m) return r;
  throw std::runtime_error(std::string("no run for mode ") + toString(m));
}

class IcpSlamMovingStart : public ::testing::TestWithParam<std::string> {};

// Plain icp-slam starts standing still at the origin with an empty map; at 6.5-21 m/s and 10 Hz
// each scan is 0.65-2.1 m ahead of the first guess, beyond its 0.5 m matching distance, so it
// stays behind (in the tunnel nothing along the axis can tell it otherwise). A path that stops
// has an ATE of about L / sqrt(12) = 0.29 L over a straight path of length L. The run fed with
// Doppler-inertial odometry gets each scan's first guess within centimetres (the odometry alone
// drifts by < 1 % of the distance, test_doppler_inertial_odometry), so ICP only refines it.
// Margin asserted: the fed run's ATE at most a quarter of the plain run's, and below 5 % of the
// distance; the plain run's ATE at least 10 % of it (it really fails: the comparison means
// something).
TEST_P(IcpSlamMovingStart, FedWithOdometryBeatsPlainByAClearMargin) {
  const PresetRun& r = run(GetParam());
  ASSERT_EQ(r.rc, 0) << r.log;
  ASSERT_EQ(r.app.runs.size(), 3u) << r.log;
  const auto& plain = byMode(r.app, IcpSeedMode::Plain);
  const auto& fed = byMode(r.app, IcpSeedMode::Odometry);
  ASSERT_TRUE(plain.errors && fed.errors) << r.log;
  const double L = plain.errors->length;
  EXPECT_GT(L, 15.0) << r.log;
  EXPECT_GT(plain.errors->ate_rmse, 0.10 * L) << r.log;
  EXPECT_LT(fed.errors->ate_rmse, 0.25 * plain.errors->ate_rmse) << r.log;
  EXPECT_LT(fed.errors->ate_rmse, 0.05 * L) << r.log;
  EXPECT_LT(fed.errors->end_point, 0.25 * plain.errors->end_point) << r.log;
}

// The seed alone (map, pose, velocity at the state time) carries icp-slam while its one odometry
// reading is fresh: CRobot2DPoseEstimator extrapolates with it for max_odometry_age = 1 s. Over
// that first second the plain run, standing still, has an ATE of about 0.29 v (1.9-6 m here),
// while the seeded run follows the truth up to what ICP itself adds: 5 cm in the street, 0.2-0.5 m
// in the tunnel, where ICP has no grip along the axis and its matches at the end of the mapped
// walls pull it back (measured: ratio 3.9 on tunnel_wheeled, 20-120 elsewhere). Margin asserted:
// at most half the plain run's ATE. (After that second icp-slam has no motion prior any more and
// falls behind like the plain run: docs/icp_slam.md.)
TEST_P(IcpSlamMovingStart, SeedCarriesTheFirstSecond) {
  const PresetRun& r = run(GetParam());
  ASSERT_EQ(r.rc, 0) << r.log;
  const auto& plain = byMode(r.app, IcpSeedMode::Plain);
  const auto& seeded = byMode(r.app, IcpSeedMode::Seeded);
  std::vector<TruthSample> truth = readTruthCsv(truthPathFor(r.app.params.rawlog));
  const double t0 = r.app.freeinit.state.timestamp;
  const PathErrors p = comparePathWithTruth(plain.path, truth, t0, t0 + 1.0);
  const PathErrors s = comparePathWithTruth(seeded.path, truth, t0, t0 + 1.0);
  EXPECT_LT(s.ate_rmse, 0.5 * p.ate_rmse)
      << "seeded " << s.ate_rmse << " plain " << p.ate_rmse << "\n"
      << r.log;
}

INSTANTIATE_TEST_SUITE_P(WheeledAndVehicular, IcpSlamMovingStart,
                         ::testing::Values("dyna_05", "dyna_06", "tunnel_wheeled",
                                           "tunnel_vehicular"));

// A start at rest (stat_02: 2 s still, then 1.5 m/s on the sidewalk): the seed pose is at the
// window start, closer than icp-slam's localization distance. Handed over naively (pose prior in
// initialize() plus odometry readings) icp-slam 2.5.8 waits for odometry to show that distance,
// cannot see it (the prior's wall-clock stamp hides it) and never corrects again: the fed run then
// stopped at the start (6 s run: end-point error 3.8 m over 5.9 m; handed over as below, 0.06 m).
// Asserted: the fed run follows the truth (end-point within 10 % of the path) and the seeded run
// moves too (end-point within half of it).
TEST(IcpSlamStaticStart, SeedAndOdometryDoNotFreezeIcpSlam) {
  const PresetRun& r = run("stat_02", 4.0);
  ASSERT_EQ(r.rc, 0) << r.log;
  const auto& seeded = byMode(r.app, IcpSeedMode::Seeded);
  const auto& fed = byMode(r.app, IcpSeedMode::Odometry);
  ASSERT_TRUE(seeded.errors && fed.errors) << r.log;
  const double L = fed.errors->length;
  EXPECT_GT(L, 1.5) << r.log;
  EXPECT_LT(fed.errors->end_point, 0.1 * L) << r.log;
  EXPECT_LT(seeded.errors->end_point, 0.5 * L) << r.log;
}

// What icp-slam writes, per mode; the final maps and the export hold stock MRPT classes only, the
// export has no IMU; the stock icp-slam app on the export reproduces the app's final pose in
// every mode.
TEST(IcpSlamOutputs, StockFilesAndStockAppReproducesTheRun) {
  const PresetRun& r = run("tunnel_vehicular");
  ASSERT_EQ(r.rc, 0) << r.log;
  const fs::path out = r.app.params.out_dir, ex = r.app.params.export_dir;
  EXPECT_TRUE(fs::is_regular_file(out / "trajectories.png"));
  EXPECT_TRUE(fs::is_regular_file(out / "results.txt"));
  for (const auto& run : r.app.runs) {
    const fs::path d = out / toString(run.mode);
    for (const char* f : {"_finalmap_.simplemap", "log_estimated_path.txt",
                          "estimated_path_tum.txt", "errors_wrt_gt.ini"})
      EXPECT_TRUE(fs::is_regular_file(d / f)) << d / f;
    mrpt::maps::CSimpleMap map;
    ASSERT_TRUE(map.loadFromFile((d / "_finalmap_.simplemap").string()));
    EXPECT_EQ(map.size(), run.keyframes);
    for (std::size_t k = 0; k < map.size(); ++k)
      for (const auto& o : *map.getAsPair(k).sf)
        EXPECT_EQ(std::string(o->GetRuntimeClass()->className).rfind("mrpt::", 0), 0u);

    const std::string name = toString(run.mode);
    const auto records = readRawlog((ex / (name + ".rawlog")).string());
    ASSERT_FALSE(records.empty());
    for (const auto& rec : records) {
      const std::string cls = rec.obs->GetRuntimeClass()->className;
      EXPECT_TRUE(cls == "mrpt::obs::CObservation2DRangeScan" ||
                  cls == "mrpt::obs::CObservationOdometry" ||
                  cls == "mrpt::obs::CObservationPointCloud")
          << cls;
    }
    const std::string cmd = "icp-slam " + (ex / (name + ".ini")).string() + " < /dev/null > " +
                            (ex / (name + ".log")).string() + " 2>&1";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    // The stock app (mrpt-apps): its last logged pose is ours.
    std::ifstream f(ex / (name + "_icp_slam_out") / "log_estimated_path.txt");
    std::string line, last;
    while (std::getline(f, line))
      if (!line.empty()) last = line;
    std::istringstream is(last);
    int step = 0;
    double x = 0, y = 0, yaw = 0;
    ASSERT_TRUE(is >> step >> x >> y >> yaw) << last;
    EXPECT_NEAR(x, run.path.back().pose.x, 1e-3) << name;
    EXPECT_NEAR(y, run.path.back().pose.y, 1e-3) << name;
    EXPECT_NEAR(yaw, run.path.back().pose.phi, 1e-4) << name;
  }
}

// The pieces of the hand-over, closed form.
TEST(IcpSlamBridge, PathErrorsAfterAlignment) {
  // A straight 30 m truth; the estimate is the same path in another SE(2) frame: no error.
  std::vector<TruthSample> truth;
  for (int k = 0; k <= 300; ++k) {
    TruthSample t;
    t.t = 100 + 0.01 * k;
    t.p_w = Vec3(10.0 * (t.t - 100), 2.0, 1.0);
    truth.push_back(t);
  }
  const mrpt::poses::CPose2D frame(5.0, -3.0, 0.5);
  std::vector<PlanarPathSample> moved, stuck;
  for (int k = 0; k <= 30; ++k) {
    const double t = 100 + 0.1 * k;
    const auto p = frame + mrpt::poses::CPose2D(10.0 * (t - 100), 2.0, 0.0);
    moved.push_back({t, p.asTPose()});
    stuck.push_back({t, mrpt::math::TPose2D(1, 1, 0)});
  }
  const PathErrors e = comparePathWithTruth(moved, truth, 100.0);
  EXPECT_NEAR(e.ate_rmse, 0.0, 1e-9);
  EXPECT_NEAR(e.end_point, 0.0, 1e-9);
  EXPECT_NEAR(e.length, 30.0, 1e-9);
  // A path that stopped: RMSE of 31 equally spaced points about their centroid over L = 30 m,
  // sqrt((n^2 - 1) / 12) * 1 m with n = 31 (-> L / sqrt(12) for dense sampling); the end point is
  // L / 2 from the centroid.
  const PathErrors st = comparePathWithTruth(stuck, truth, 100.0);
  EXPECT_NEAR(st.ate_rmse, std::sqrt((31.0 * 31.0 - 1) / 12.0), 1e-9);
  EXPECT_NEAR(st.end_point, 15.0, 1e-9);
  // The window selects samples.
  EXPECT_EQ(comparePathWithTruth(moved, truth, 101.0, 102.0).samples, 11u);
  EXPECT_THROW(comparePathWithTruth(moved, truth, 200.0), std::runtime_error);
}

TEST(IcpSlamBridge, ScanIsTheLevelledSliceAroundTheLidar) {
  // A wall 10 m ahead of the body, seen by a LiDAR 0.5 m above the body and pitched 10 deg down;
  // the frame's points span heights -2..3 m above the body. Levelled, the slice [-0.3, 1.5] m
  // keeps the points between those heights, all at x = 10 m.
  Extrinsics e;
  e.R_bl = Eigen::AngleAxisd(10 * M_PI / 180, Vec3::UnitY()).toRotationMatrix();
  e.p_bl = Vec3(0, 0, 0.5);
  LidarFrame f;
  f.stamp = 50.0;
  for (int i = 0; i <= 50; ++i) {
    DopplerPoint p;
    const Vec3 p_b(10.0, 0.0, -2.0 + 0.1 * i);
    p.p_l = (e.R_bl.transpose() * (p_b - e.p_bl)).cast<float>();
    p.time_offset = 0.001f * static_cast<float>(i);
    f.points.push_back(p);
  }
  ScanSliceParams sp;
  const auto scan = scanFromFrame(f, e, Mat3::Identity(), sp, "LIDAR");
  ASSERT_EQ(scan->getScanSize(), 361u);
  EXPECT_NEAR(toUnix(scan->timestamp), 50.025, 1e-6);  // mean point time
  EXPECT_NEAR(scan->sensorPose.z(), 0.5, 1e-12);
  std::size_t valid = 0;
  for (std::size_t i = 0; i < scan->getScanSize(); ++i) {
    if (!scan->getScanRangeValidity(i)) continue;
    ++valid;
    EXPECT_EQ(i, 180u);  // straight ahead
    EXPECT_NEAR(scan->getScanRange(i), 10.0, 1e-5);
  }
  EXPECT_EQ(valid, 1u);
  // Too high a slice: nothing.
  sp.z_min = 3.5;
  sp.z_max = 4.0;
  const auto none = scanFromFrame(f, e, Mat3::Identity(), sp, "LIDAR");
  for (std::size_t i = 0; i < none->getScanSize(); ++i) EXPECT_FALSE(none->getScanRangeValidity(i));
}

TEST(IcpSlamBridge, SeedPoseCovarianceAndVelocity) {
  InitResult r;
  InitialState& s = r.state;
  s.status = InitStatus::Ok;
  s.timestamp = 10;
  const double yaw = 0.3;
  s.q_wb = Quat(Eigen::AngleAxisd(yaw, Vec3::UnitZ()) * Eigen::AngleAxisd(0.05, Vec3::UnitX()));
  s.p_w = Vec3(4, 5, 1);
  s.v_w = Eigen::AngleAxisd(yaw, Vec3::UnitZ()) * Vec3(7, 0.5, 0.1);
  s.cov = Cov18::Identity() * 1e-4;
  s.cov(kTheta + 2, kTheta + 2) = 4e-4;  // right perturbation about body z
  MapPoint m;
  m.p_w = Eigen::Vector3f(10, 5, 1.5);  // in the slice
  r.static_map.push_back(m);
  m.p_w = Eigen::Vector3f(10, 5, -1.0);  // the road: out
  r.static_map.push_back(m);
  const IcpSeed seed = makeIcpSeed(r, ScanSliceParams());
  EXPECT_NEAR(seed.pose.mean.x(), 4, 1e-12);
  EXPECT_NEAR(seed.pose.mean.y(), 5, 1e-12);
  EXPECT_NEAR(seed.pose.mean.phi(), yaw, 1e-12);
  EXPECT_EQ(seed.map_points, 1u);
  EXPECT_NEAR(seed.velocity_local.vx, 7, 1e-12);
  EXPECT_NEAR(seed.velocity_local.vy, 0.5, 1e-12);
  EXPECT_NEAR(seed.pose.cov(0, 0), 1e-4, 1e-15);
  // yaw variance = var of z of R_wb dtheta: with a 0.05 rad roll, cos^2 * 4e-4 + sin^2 * 1e-4.
  const double c = std::cos(0.05), sn = std::sin(0.05);
  EXPECT_NEAR(seed.pose.cov(2, 2), c * c * 4e-4 + sn * sn * 1e-4, 1e-12);
}

TEST(IcpSlamInputs, BadIniIsAClearError) {
  const fs::path dir = testDir("bad_ini");
  const std::string ini = (dir / "icp.ini").string();
  std::ofstream(ini) << "[ICP]\n[MappingApplication]\n[freeinit_scan]\nz_mn = 1\n";
  IcpSlamApp app;
  app.params.icp_ini = ini;
  app.params.freeinit_ini = kSrc + "/ini/freeinit.ini";
  app.params.rawlog = kSrc + "/rawlogs/dyna_01.rawlog";
  app.params.out_dir = (dir / "out").string();
  std::ostringstream log;
  try {
    app.run(log);
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("z_mn"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(ini), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir / "out"));
}

TEST(IcpSlamInputs, FailedRunLeavesTheEarlierOutputAsItWas) {
  // The files of an earlier run (results of every mode, the export) and one the app does not own:
  // a run that fails replaces nothing (earlier results go only for a complete new set).
  const fs::path dir = testDir("stale");
  const fs::path out = dir / "out", ex = dir / "export";
  const std::vector<fs::path> stale = {out / "results.txt",
                                       out / "odometry_alone_tum.txt",
                                       out / "icp_slam_seed.ini",
                                       out / "trajectories.png",
                                       out / "odometry" / "errors_wrt_gt.ini",
                                       out / "plain" / "estimated_path_tum.txt",
                                       out / "seeded" / "_finalmap_.simplemap",
                                       ex / "seeded.rawlog",
                                       ex / "plain.ini"};
  const fs::path foreign = out / "notes.txt";
  for (const auto& f : stale) {
    fs::create_directories(f.parent_path());
    std::ofstream(f) << "earlier run\n";
  }
  std::ofstream(foreign) << "mine\n";
  IcpSlamApp app;
  app.params.icp_ini = kSrc + "/ini/icp_slam.ini";
  app.params.freeinit_ini = kSrc + "/ini/freeinit.ini";
  app.params.rawlog = (dir / "missing.rawlog").string();  // bad input: no such file
  app.params.out_dir = out.string();
  app.params.export_dir = ex.string();
  std::ostringstream log;
  EXPECT_ANY_THROW(app.run(log));
  for (const auto& f : stale) {
    std::ifstream in(f);
    std::string line;
    EXPECT_TRUE(std::getline(in, line)) << f;
    EXPECT_EQ(line, "earlier run") << f;
  }
  EXPECT_TRUE(fs::exists(foreign));
}

}  // namespace
