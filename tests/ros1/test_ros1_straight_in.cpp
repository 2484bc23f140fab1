// ROS 1 bags straight into the apps (app_support/recording_source.h over ros1::Ros1Reader):
// freeinit on a bag is freeinit on its import, to the last digit (one start, --start, --every;
// against the truth beside either); a window of a long bag reads the bag's index and the chunks of
// the window, not the file (counted by the reader's guard and by the bytes the process read); a bag
// damaged outside the window does not stop a window that does not need the damaged chunk, and one
// damaged inside it is one line naming the file and the byte. The truth file is found beside a
// rawlog, an MCAP file, a bag, a .db3 or a rosbag2 folder, and freeinit-eval-rawlog evaluates
// against it. Bags are written in-test with the project's bag writer from simulator recordings.
#include <freeinit/app_support/app_config.h>
#include <freeinit/app_support/checked_recording.h>
#include <freeinit/app_support/ground_truth.h>
#include <freeinit/bags/ros2_import.h>
#include <freeinit/mrpt_plugins/rawlog_reader.h>
#include <freeinit/ros1/bag_reader.h>
#include <freeinit/ros1/bag_writer.h>
#include <freeinit/sim/simulator.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <optional>
#include <sstream>

#include "bag_import_app.h"
#include "eval_rawlog_app.h"
#include "free_init_app.h"
#include "free_init_runs.h"
#include "ros_test_files.h"
#include "sim_app.h"

using namespace freeinit;
using namespace freeinit::apps;
namespace fs = std::filesystem;

namespace {

const std::string kRecordings = FREEINIT_ROS2_RECORDINGS;

std::string dir(const std::string& name) {
  return test::testFolder("freeinit_ros1_straight_in_tests", name);
}

// The handheld rotational start (dyna_01) for `duration` s with `points` points per frame, as
// freeinit-sim records it: its rawlog and its truth file in `d`.
struct Simulated {
  sim::Recording rec;
  std::string rawlog, truth;
};

Simulated simulate(const std::string& d, double duration, int points) {
  SimApp sim;
  auto sc = sim::preset("dyna_01", 1);
  sc.duration = duration;
  sc.points_per_frame = points;
  sim.params.preset = sc.name;
  sim.params.seed = sc.seed;
  sim.params.duration = sc.duration;
  sim.params.points_per_frame = sc.points_per_frame;
  sim.params.output = d + "/sim.rawlog";
  std::ostringstream log;
  sim.run(log);
  return {sim::simulate(sc), sim.params.output, app_support::truthPathFor(sim.params.output)};
}

// The recording as a ROS 1 bag in the release's layout, its extrinsics on /tf_static.
std::string writeBag(const std::string& path, const sim::Recording& rec,
                     ros1::BagWriteOptions o = {}) {
  ros2::TransformStamped tf;
  tf.header.frame_id = o.imu_frame_id;
  tf.child_frame_id = o.lidar_frame_id;
  const Eigen::Quaterniond q(rec.declared_extrinsics.R_bl);
  tf.rotation = {q.x(), q.y(), q.z(), q.w()};
  const Vec3& p = rec.declared_extrinsics.p_bl;
  tf.translation = {p.x(), p.y(), p.z()};
  o.tf_static = {tf};
  ros1::writeBag(path, rec.imu, rec.frames, o);
  return path;
}

std::string import(const std::string& bag, const std::string& out) {
  BagImportApp app;
  app.params.bag = bag;
  app.params.config_file = test::writeText(out + ".import.ini", "[bag_import]\n");
  app.params.output = out;
  app.params.progress = false;
  std::ostringstream log;
  app.run(log);
  return out;
}

using test::AppRun;
using test::runFreeInit;

// [bytes] read by this process so far (Linux: every read(2), whoever made it).
std::uint64_t bytesReadByProcess() {
  std::ifstream io("/proc/self/io");
  std::string key;
  std::uint64_t value = 0;
  while (io >> key >> value)
    if (key == "rchar:") return value;
  return 0;
}

std::uint64_t u32At(const std::string& b, std::size_t at) {
  std::uint32_t v;
  std::memcpy(&v, b.data() + at, 4);
  return v;
}

}  // namespace

TEST(Ros1StraightIn, FreeInitOnABagIsFreeInitOnItsImport) {
  const std::string d = dir("run");
  const Simulated sim = simulate(d, 2.0, 3000);
  const std::string bag = writeBag(d + "/rec.bag", sim.rec);
  const std::string rawlog = import(bag, d + "/imported.rawlog");
  // The truth beside both: errors_wrt_gt.ini in both outputs.
  fs::copy_file(sim.truth, app_support::truthPathFor(bag));
  fs::copy_file(sim.truth, app_support::truthPathFor(rawlog));
  const std::string ini = test::writeText(d + "/freeinit.ini", "[bag_import]\n");
  struct Case {
    std::optional<double> start;
    double every;
  };
  for (const Case& c : {Case{std::nullopt, 0}, Case{0.6, 0}, Case{std::nullopt, 0.5}}) {
    const std::string name =
        "start_" + std::to_string(c.start.value_or(0)) + "_every_" + std::to_string(c.every);
    const AppRun from_rawlog = runFreeInit(ini, rawlog, d + "/rawlog_" + name, c.start, c.every);
    const AppRun straight = runFreeInit(ini, bag, d + "/bag_" + name, c.start, c.every);
    EXPECT_EQ(straight.files, from_rawlog.files) << name;
    const std::size_t states = std::count_if(
        straight.files.begin(), straight.files.end(),
        [](const auto& f) { return fs::path(f.first).filename() == "initial_state.ini"; });
    const std::size_t errors = std::count_if(
        straight.files.begin(), straight.files.end(),
        [](const auto& f) { return fs::path(f.first).filename() == "errors_wrt_gt.ini"; });
    EXPECT_EQ(states, c.every > 0 ? 4u : 1u) << name;  // --every 0.5: 0, 0.5, 1 and 1.5 s
    EXPECT_GE(errors, 1u) << name;
    // The extrinsics came from the bag's /tf_static, those of the import from the same.
    EXPECT_EQ(straight.log.find("Warning"), std::string::npos) << straight.log;
  }

  // The INI's extrinsics win over /tf_static, a disagreement is one warning line; neither is an
  // error naming the bag.
  const std::string given = test::writeText(d + "/given.ini",
                                            "[bag_import]\n[extrinsics]\nfrom_sensor_pose = false\n"
                                            "R_bl = 1 0 0 0 1 0 0 0 1\np_bl = 0 0 0\n");
  EXPECT_CONTAINS(runFreeInit(given, bag, d + "/given").log,
                  "[extrinsics] and /tf_static of " + bag + " (imu -> aeva) differ by ");
  ros1::writeBag(d + "/no_tf.bag", sim.rec.imu, sim.rec.frames, ros1::BagWriteOptions());
  try {
    runFreeInit(ini, d + "/no_tf.bag", d + "/no_tf");
    ADD_FAILURE() << "ran without extrinsics";
  } catch (const std::exception& e) {
    EXPECT_CONTAINS(e.what(), d + "/no_tf.bag: a ROS 1 bag: no /tf_static linking the IMU's frame "
                                  "to the LiDAR's");
  }

  // freeinit-eval-rawlog: the bag and its import give the same rows.
  auto evaluate = [&](const std::string& input) {
    EvalRawlogApp app;
    app.params.config_file = ini;
    app.params.rawlogs = {input};
    app.params.jobs = 1;
    app.params.baselines = false;
    std::ostringstream log;
    app.run(log);
    return app.rows;
  };
  const auto rows_bag = evaluate(bag);
  const auto rows_rawlog = evaluate(rawlog);
  ASSERT_EQ(rows_bag.size(), rows_rawlog.size());
  ASSERT_FALSE(rows_bag.empty());
  for (std::size_t i = 0; i < rows_bag.size(); ++i) {
    EXPECT_EQ(rows_bag[i].status, "ok");
    EXPECT_EQ(rows_bag[i].velocity_err, rows_rawlog[i].velocity_err);
    EXPECT_EQ(rows_bag[i].gravity_err_deg, rows_rawlog[i].gravity_err_deg);
    EXPECT_EQ(rows_bag[i].gyro_bias_err, rows_rawlog[i].gyro_bias_err);
    EXPECT_EQ(rows_bag[i].nees_velocity, rows_rawlog[i].nees_velocity);
  }
}

// A long bag (120 s, 53 chunks of rosbag's 768 KB): a window reads the index and its own chunks.
TEST(Ros1StraightIn, AWindowReadsTheChunksItNeedsNotTheBag) {
  const std::string d = dir("long");
  const Simulated sim = simulate(d, 120.0, 1000);
  const std::string bag = writeBag(d + "/long.bag", sim.rec);
  const auto bag_bytes = fs::file_size(bag);

  // The reader: one second of bag time at the start, then the whole bag.
  bags::BagImportConfig config;
  const double t0 = sim.rec.imu.front().t;
  {
    ros1::Ros1Reader reader(bag, config);
    const std::size_t chunks = reader.checked().index().chunks.size();
    EXPECT_GT(chunks, 50u);
    EXPECT_EQ(reader.checked().chunksChecked(), 0u);  // opening reads the index only
    EXPECT_LT(reader.checked().bytesRead(), bag_bytes / 50);
    bags::BagReadCallbacks cb;
    std::size_t imu = 0;
    cb.imu = [&](const ImuSample&) { ++imu; };
    cb.frame = [](LidarFrame&&) {};
    bags::ImportStream stream(config, cb);
    reader.start(static_cast<std::int64_t>(t0 * 1e9), static_cast<std::int64_t>((t0 + 1) * 1e9));
    while (reader.step(stream)) {
    }
    stream.finish("imu");
    EXPECT_GT(imu, 150u);
    const std::size_t window_chunks = reader.checked().chunksChecked();
    EXPECT_LE(window_chunks, chunks / 10) << window_chunks << " of " << chunks;
    EXPECT_LT(reader.checked().bytesRead(), bag_bytes / 10)
        << reader.checked().bytesRead() << " of " << bag_bytes << " bytes, " << window_chunks
        << " of " << chunks << " chunks";
    reader.start();
    bags::ImportStream all(config, cb);
    while (reader.step(all)) {
    }
    EXPECT_EQ(reader.checked().chunksChecked(), chunks);
  }

  // The app, as users run it: the bytes the process read, at the start and at --start 15.
  const std::string ini = test::writeText(d + "/freeinit.ini", "[bag_import]\n");
  for (const std::optional<double> start : {std::optional<double>(), std::optional<double>(60.0)}) {
    const std::uint64_t before = bytesReadByProcess();
    const AppRun r = runFreeInit(ini, bag, d + "/out_" + std::to_string(start.value_or(0)), start);
    const std::uint64_t read = bytesReadByProcess() - before;
    EXPECT_EQ(r.files.count("initial_state.ini"), 1u);
    // About 9 % at the start, 15 % at 60 s (the first record, then the window from 2 s before
    // the start), each window chunk read twice (the guard, then librosbag); the index ~2 %.
    EXPECT_LT(read, bag_bytes / 6) << read << " of " << bag_bytes << " bytes read";
  }
  // Reading it all reads at least the file: the count is real.
  const std::uint64_t before = bytesReadByProcess();
  ros1::Ros1Reader reader(bag, config);
  bags::BagReadCallbacks cb;
  std::size_t imu = 0;
  cb.imu = [&](const ImuSample&) { ++imu; };
  cb.frame = [](LidarFrame&&) {};
  bags::ImportStream all(config, cb);
  reader.start();
  while (reader.step(all)) {
  }
  all.finish("imu");
  EXPECT_EQ(imu, sim.rec.imu.size());
  EXPECT_GE(bytesReadByProcess() - before, bag_bytes);
}

// Damage in a chunk the window does not need is not read; in one it needs, it is one line naming
// the file and the byte. A cut bag (its index gone) is one line too.
TEST(Ros1StraightIn, DamagedBagsAreOneLineAndOnlyWhatIsReadIsChecked) {
  const std::string d = dir("bad");
  const Simulated sim = simulate(d, 10.0, 400);
  ros1::BagWriteOptions o;
  o.chunk_threshold = 64 * 1024;
  const std::string bag = writeBag(d + "/ok.bag", sim.rec, o);
  const std::string ini = test::writeText(d + "/freeinit.ini", "[bag_import]\n");
  std::string b = test::fileBytes(bag);
  // The first record in the data of the last chunk: a header length far beyond the chunk.
  std::uint64_t pos = 0;
  {
    ros1::Ros1Reader reader(bag, bags::BagImportConfig());
    pos = reader.checked().index().chunks.back().pos;
  }
  const std::size_t data_at = pos + 4 + u32At(b, pos) + 4;
  const std::uint32_t huge = 0x7fffffff;
  std::memcpy(&b[data_at], &huge, 4);
  const std::string damaged = d + "/damaged.bag";
  std::ofstream(damaged, std::ios::binary) << b;

  const AppRun early = runFreeInit(ini, damaged, d + "/early");
  EXPECT_EQ(early.files.count("initial_state.ini"), 1u);
  try {
    runFreeInit(ini, damaged, d + "/late", 9.0);
    ADD_FAILURE() << "the damaged chunk was read without an error";
  } catch (const std::exception& e) {
    const std::string what = e.what();
    EXPECT_CONTAINS(what, damaged + ": byte " + std::to_string(pos) +
                              ": chunk: byte 4 of its data: record in the chunk: a record "
                              "header of 2147483647 bytes");
    EXPECT_CONTAINS(what, "(corrupt bag)");
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }

  std::string cut = test::fileBytes(bag);
  cut.resize(cut.size() - 100);
  std::ofstream(d + "/cut.bag", std::ios::binary) << cut;
  try {
    runFreeInit(ini, d + "/cut.bag", d + "/cut");
    ADD_FAILURE() << "a cut bag was read";
  } catch (const std::exception& e) {
    const std::string what = e.what();
    EXPECT_CONTAINS(what, d + "/cut.bag: byte ");
    EXPECT_CONTAINS(what, "truncated bag?");
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
}

TEST(GroundTruth, TheTruthFileSitsBesideTheRecording) {
  using app_support::truthPathFor;
  EXPECT_EQ(truthPathFor("a/rec.rawlog"), "a/rec.truth.csv");
  EXPECT_EQ(truthPathFor("rec.rawlog"), "rec.truth.csv");
  EXPECT_EQ(truthPathFor("a/rec.mcap"), "a/rec.truth.csv");
  EXPECT_EQ(truthPathFor("a/rec.bag"), "a/rec.truth.csv");
  EXPECT_EQ(truthPathFor("a/rec_0.db3"), "a/rec_0.truth.csv");
  EXPECT_EQ(truthPathFor("a/rec"), "a/rec.truth.csv");   // a rosbag2 folder
  EXPECT_EQ(truthPathFor("a/rec/"), "a/rec.truth.csv");  // beside it, not in it
  EXPECT_EQ(truthPathFor("a/rec.txt"), "a/rec.txt.truth.csv");
}

// freeinit-eval-rawlog rec.mcap: against the truth beside it (here a constant state covering the
// recording: the errors are not the point, finding the truth is).
TEST(GroundTruth, EvalRawlogFindsTheTruthBesideAnMcapFile) {
  const std::string d = dir("mcap");
  const std::string mcap = d + "/rec.mcap";
  fs::copy_file(kRecordings + "/imu_cloud.mcap", mcap);
  double first = 0, last = 0;
  bags::BagReadCallbacks cb;
  cb.imu = [&](const ImuSample& s) { (first == 0 ? first : last) = s.t; };
  cb.frame = [](LidarFrame&&) {};
  bags::readRos2Recording(mcap, bags::BagImportConfig(), cb);
  const std::string ini = test::writeText(d + "/eval.ini", "[window]\nduration = 0.25\n");
  EvalRawlogApp app;
  app.params.config_file = ini;
  app.params.rawlogs = {mcap};
  app.params.jobs = 1;
  app.params.baselines = false;
  std::ostringstream log;
  try {
    app.run(log);
    ADD_FAILURE() << "evaluated without truth";
  } catch (const std::exception& e) {
    EXPECT_CONTAINS(e.what(), mcap + ": no ground truth (expected " + d + "/rec.truth.csv)");
  }
  std::vector<app_support::TruthSample> truth;
  for (double t = first - 1; t <= last + 1; t += 0.01) {
    app_support::TruthSample s;
    s.t = t;
    truth.push_back(s);
  }
  app_support::writeTruthCsv(d + "/rec.truth.csv", truth);
  app.run(log);
  ASSERT_FALSE(app.rows.empty());
  EXPECT_EQ(app.rows.front().source, mcap);
}
