// The importer on ROS 2 recordings written by independent writers (tests/ros2/fixtures: @mcap/core,
// @foxglove/cdr, SQLite) and on the same data recorded as a ROS 1 bag: every container gives the
// same rawlog, byte for byte; the extrinsics come from /tf_static of either generation unless the
// INI gives them (a disagreement is one warning line); app-level messages name the file.
#include <freeinit/app_support/file_kind.h>
#include <freeinit/bags/ros2_import.h>
#include <freeinit/bags/static_transforms.h>
#include <freeinit/ros1/bag_reader.h>
#include <freeinit/ros1/bag_writer.h>
#include <freeinit/ros2/message_decoding.h>
#include <freeinit/ros2/open_recording.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>

#include "bag_import_app.h"
#include "free_init_app.h"
#include "free_init_runs.h"
#include "ros_test_files.h"

using namespace freeinit;
using namespace freeinit::apps;
namespace fs = std::filesystem;

namespace {

const std::string kRecordings = FREEINIT_ROS2_RECORDINGS;
std::string fixture(const std::string& name) { return kRecordings + "/" + name; }

std::string dir(const std::string& name) {
  return test::testFolder("freeinit_ros_generations_tests", name);
}

const char* const kIniExtrinsics = "[extrinsics]\nR_bl = 1 0 0 0 1 0 0 0 1\np_bl = 0 0 0\n";

// The fixtures' LiDAR pose in the IMU frame (generate.mjs: imu_link -> aeva_link).
Extrinsics fixtureExtrinsics() {
  Extrinsics e;
  e.R_bl = Eigen::AngleAxisd(M_PI / 2, Vec3::UnitZ()).toRotationMatrix();
  e.p_bl = Vec3(0.018, 0.0, -0.0434);
  return e;
}

struct Imported {
  std::string rawlog;  ///< its bytes
  std::string extrinsics_ini;
  std::string log;
  BagImportApp app;
};

Imported import(const std::string& input, const std::string& ini_text, const std::string& d) {
  Imported r;
  r.app.params.bag = input;
  r.app.params.config_file = test::writeText(d + "/import.ini", ini_text);
  r.app.params.output = d + "/out.rawlog";
  r.app.params.progress = false;
  std::ostringstream log;
  r.app.run(log);
  r.log = log.str();
  r.rawlog = test::fileBytes(d + "/out.rawlog");
  r.extrinsics_ini = test::fileBytes(d + "/out.extrinsics.ini");
  return r;
}

std::string errorOf(const std::string& input, const std::string& ini_text, const std::string& d) {
  try {
    import(input, ini_text, d);
  } catch (const std::exception& e) {
    EXPECT_FALSE(fs::exists(d + "/out.rawlog"));
    return e.what();
  }
  ADD_FAILURE() << input << ": imported";
  return "";
}

bool near(const Extrinsics& a, const Extrinsics& b, double tol) {
  return (a.R_bl - b.R_bl).cwiseAbs().maxCoeff() < tol && (a.p_bl - b.p_bl).norm() < tol;
}

}  // namespace

TEST(Ros2Import, EveryContainerGivesTheSameRawlog) {
  const Imported ref = import(fixture("imu_cloud.mcap"), "[bag_import]\n", dir("ref"));
  EXPECT_EQ(ref.app.summary.imu.imported, 80u);
  EXPECT_EQ(ref.app.summary.lidar.imported, 3u);
  EXPECT_EQ(ref.app.summary.points, 384u);
  for (const char* f : {"imu_cloud_zstd.mcap", "imu_cloud_lz4.mcap", "imu_cloud_be.mcap",
                        "imu_cloud_nosummary.mcap", "imu_cloud_unchunked.mcap", "imu_cloud_db3",
                        "imu_cloud.db3", "imu_cloud_mcap"}) {
    const Imported r = import(fixture(f), "[bag_import]\n", dir(std::string("x") + f));
    EXPECT_EQ(r.rawlog, ref.rawlog) << f;
    EXPECT_EQ(r.app.summary.imu.in_bag, 80u) << f;
  }
}

TEST(Ros2Import, TheSameDataAsARos1BagGivesTheSameRawlog) {
  // The ROS 2 recording in core types, and its /tf_static as recorded.
  bags::BagImportConfig config;
  std::vector<ImuSample> imu;
  std::vector<LidarFrame> frames;
  bags::BagReadCallbacks cb;
  cb.imu = [&](const ImuSample& s) { imu.push_back(s); };
  cb.frame = [&](LidarFrame&& f) { frames.push_back(std::move(f)); };
  bags::readRos2Recording(fixture("imu_cloud_zstd.mcap"), config, cb);
  auto rec = ros2::openRecording(fixture("imu_cloud.mcap"));
  rec->start({std::numeric_limits<std::int64_t>::min(),
              std::numeric_limits<std::int64_t>::max(),
              {rec->topic("/tf_static", ros2::kTFMessageType)}});
  ros2::Message m;
  ASSERT_TRUE(rec->next(m));
  // The same as a ROS 1 bag (the release's layout, frame ids and transforms of the recording).
  const std::string d = dir("ros1");
  ros1::BagWriteOptions o;
  o.config = config;
  o.imu_frame_id = "imu_link";
  o.lidar_frame_id = "aeva_link";
  o.tf_static = ros2::decodeTFMessage(m.data).transforms;
  o.compression = ros1::BagWriteOptions::Compression::kLz4;
  ros1::writeBag(d + "/rec.bag", imu, frames, o);

  for (const std::string& ini :
       {std::string("[bag_import]\n"), std::string("[bag_import]\n") + kIniExtrinsics}) {
    const Imported two = import(fixture("imu_cloud.mcap"), ini, dir("two"));
    const Imported one = import(d + "/rec.bag", ini, dir("one"));
    EXPECT_EQ(one.rawlog, two.rawlog) << ini;
    EXPECT_EQ(one.app.summary.points, two.app.summary.points);
    ASSERT_TRUE(one.app.recorded_extrinsics && two.app.recorded_extrinsics);
    EXPECT_EQ(one.app.recorded_extrinsics->extrinsics.R_bl,
              two.app.recorded_extrinsics->extrinsics.R_bl);
    EXPECT_EQ(one.app.recorded_extrinsics->extrinsics.p_bl,
              two.app.recorded_extrinsics->extrinsics.p_bl);
  }
}

TEST(Ros2Import, ExtrinsicsFromTfStaticUnlessTheIniGivesThem) {
  for (const char* f : {"imu_cloud.mcap", "imu_cloud_db3"}) {
    const Imported r = import(fixture(f), "[bag_import]\n", dir("tf"));
    EXPECT_TRUE(near(r.app.settings.extrinsics, fixtureExtrinsics(), 1e-12)) << f;
    EXPECT_EQ(r.app.recorded_extrinsics->chain, "imu_link -> aeva_link");
    EXPECT_CONTAINS(r.log, "extrinsics from /tf_static of ");
    EXPECT_CONTAINS(r.extrinsics_ini, "p_bl = 0.018 0 -0.0434");
    EXPECT_TRUE(r.app.extrinsics_warning.empty());
  }
  // The INI wins; a disagreement beyond 0.1 deg / 1 mm is one warning line.
  const Imported given =
      import(fixture("imu_cloud.mcap"), std::string("[bag_import]\n") + kIniExtrinsics, dir("ini"));
  EXPECT_EQ(given.app.settings.extrinsics.R_bl, Mat3::Identity());
  EXPECT_CONTAINS(given.log,
                  "[extrinsics] and /tf_static of " + fixture("imu_cloud.mcap") +
                      " (imu_link -> aeva_link) differ by 90.000 deg and 47.0 mm: the INI's are "
                      "used\n");
  // Within the tolerance: silent.
  const std::string close =
      "[bag_import]\n[extrinsics]\nyaw_deg = 90.05\np_bl = 0.0185 0.0004 -0.0434\n";
  const Imported agree = import(fixture("imu_cloud.mcap"), close, dir("close"));
  EXPECT_TRUE(agree.app.extrinsics_warning.empty()) << agree.app.extrinsics_warning;
  EXPECT_EQ(agree.log.find("Warning"), std::string::npos) << agree.log;
  // Neither: an error naming the INI key and the recording.
  EXPECT_CONTAINS(
      errorOf(fixture("imu_cloud.mcap"), "[bag_import]\ntf_static_topic = /nope\n", dir("none")),
      "[extrinsics] R_bl: extrinsics missing, and " + fixture("imu_cloud.mcap") +
          " has no /nope linking the IMU's frame to the LiDAR's");
}

TEST(StaticTransforms, AChainThroughACommonParentComposes) {
  // base -> imu and base -> lidar, both rotated: T_imu_lidar = T_base_imu^-1 T_base_lidar.
  auto tf = [](const std::string& parent, const std::string& child, const Eigen::Quaterniond& q,
               const Vec3& p) {
    ros2::TransformStamped t;
    t.header.frame_id = parent;
    t.child_frame_id = child;
    t.rotation = {q.x(), q.y(), q.z(), q.w()};
    t.translation = {p.x(), p.y(), p.z()};
    return t;
  };
  const Eigen::Quaterniond q1(Eigen::AngleAxisd(0.3, Vec3(1, 2, 3).normalized()));
  const Eigen::Quaterniond q2(Eigen::AngleAxisd(-1.1, Vec3(0, 1, 1).normalized()));
  const Vec3 p1(0.1, -0.2, 0.3), p2(-0.5, 0.05, 0.7);
  const std::vector<ros2::TransformStamped> t{
      tf("/base", "imu", q1, p1), tf("base", "lidar", q2, p2), tf("base", "camera", q2, p1)};
  const auto e = bags::extrinsicsFromTransforms(t, "imu", "/lidar");
  ASSERT_TRUE(e);
  const Mat3 R = q1.toRotationMatrix().transpose() * q2.toRotationMatrix();
  const Vec3 p = q1.toRotationMatrix().transpose() * (p2 - p1);
  EXPECT_LT((e->extrinsics.R_bl - R).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_LT((e->extrinsics.p_bl - p).norm(), 1e-14);
  EXPECT_EQ(e->chain, "imu <- base -> lidar");
  EXPECT_FALSE(bags::extrinsicsFromTransforms(t, "imu", "radar"));
  EXPECT_FALSE(bags::extrinsicsFromTransforms(t, "", "lidar"));
  EXPECT_TRUE(bags::extrinsicsFromTransforms({}, "x", "x"));  // the same frame: identity
}

TEST(Ros2Import, MessagesNameTheFileAndWhatItIs) {
  const std::string mcap = fixture("imu_cloud.mcap");
  EXPECT_CONTAINS(errorOf(mcap, "[bag_import]\nimu_topic = /imu\n", dir("topic")),
                  mcap +
                      ": an MCAP file (ROS 2): no topic /imu (set imu_topic); the recording "
                      "has: /tf_static (tf2_msgs/msg/TFMessage), /imu/data "
                      "(sensor_msgs/msg/Imu), /aeva/AeriesII/point_cloud_frame "
                      "(sensor_msgs/msg/PointCloud2)");
  EXPECT_CONTAINS(errorOf(mcap, "[bag_import]\nlidar_topic = /tf_static\n", dir("type")),
                  mcap +
                      ": topic /tf_static has type tf2_msgs/msg/TFMessage, expected "
                      "sensor_msgs/msg/PointCloud2 (lidar_topic)");
  EXPECT_CONTAINS(
      errorOf(mcap, "[bag_import]\nstamp_source = trigger\ntrigger_topic = /t\n", dir("trigger")),
      "stamp_source = trigger matches clouds to triggers by header.seq, which ROS 2 "
      "headers do not have");
  EXPECT_CONTAINS(errorOf(fixture("tf_bz2.mcap"), "[bag_import]\n", dir("bz2")),
                  "compressed with 'bz2', which is not supported");
  // A folder of .db3 files without metadata.yaml.
  const std::string d = dir("plain");
  fs::create_directories(d + "/run1");
  fs::copy_file(fixture("imu_cloud.db3"), d + "/run1/a_0.db3");
  EXPECT_CONTAINS(errorOf(d + "/run1", "[bag_import]\n", dir("plain_out")),
                  d + "/run1: a rosbag2 folder without metadata.yaml");
  // A cut MCAP file imports what is whole, and says so.
  const Imported killed = import(fixture("imu_cloud_killed.mcap"), "[bag_import]\n", dir("cut"));
  EXPECT_CONTAINS(killed.log, "warning: the file ends at byte 29456");
}

TEST(Ros2Import, DefaultOutputNames) {
  EXPECT_EQ(defaultRawlogName("a/rec.mcap"), "a/rec.rawlog");
  EXPECT_EQ(defaultRawlogName("a/rec.db3"), "a/rec.rawlog");
  EXPECT_EQ(defaultRawlogName("a/rec.bag"), "a/rec.rawlog");
  EXPECT_EQ(defaultRawlogName(fixture("imu_cloud_db3") + "/"), fixture("imu_cloud_db3.rawlog"));
}

// ---------------------------------------------------------------------------------------------
// Straight in: freeinit on the recording is freeinit on its import, to the last digit.
namespace {

std::map<std::string, std::string> runFreeInit(const std::string& input, const std::string& out,
                                               std::optional<double> start = std::nullopt) {
  // The fixtures hold 0.4 s: a window that fits in them (the default 0.5 s is refused as longer
  // than the recording).
  const std::string ini = test::writeText(out + ".ini", "[window]\nduration = 0.25\n");
  return test::runFreeInit(ini, input, out, start).files;
}

}  // namespace

TEST(StraightIn, FreeInitOnARecordingIsFreeInitOnItsImport) {
  const std::string d = dir("run");
  const Imported imported = import(fixture("imu_cloud.mcap"), "[bag_import]\n", d);
  for (const auto& start : {std::optional<double>(), std::optional<double>(0.1)}) {
    const auto from_rawlog = runFreeInit(d + "/out.rawlog", d + "/rawlog_out", start);
    for (const char* f : {"imu_cloud.mcap", "imu_cloud_db3", "imu_cloud.db3"}) {
      const auto straight = runFreeInit(fixture(f), d + "/" + f + "_out", start);
      EXPECT_EQ(straight, from_rawlog) << f;
    }
    EXPECT_EQ(from_rawlog.count("initial_state.ini"), 1u);
  }
}

TEST(StraightIn, InputKindsAreRecognisedAndNamed) {
  using app_support::FileKind;
  EXPECT_EQ(app_support::fileKind(fixture("imu_cloud.mcap")), FileKind::Mcap);
  EXPECT_EQ(app_support::fileKind(fixture("imu_cloud.db3")), FileKind::Sqlite);
  EXPECT_EQ(app_support::fileKind(fixture("imu_cloud_db3")), FileKind::Rosbag2Folder);
  EXPECT_EQ(app_support::fileKind(kRecordings), FileKind::Folder);
  for (auto k : {FileKind::Mcap, FileKind::Sqlite, FileKind::Rosbag2Folder})
    EXPECT_TRUE(app_support::isReadableInput(k));
  EXPECT_EQ(app_support::describe(FileKind::Mcap), "an MCAP file (ROS 2)");
  FreeInitAppParams p;
  p.rawlog = fixture("imu_cloud.mcap");
  EXPECT_EQ(p.argumentsProblem(), "");
  // A folder of recordings without metadata.yaml: the reader names it and lists what it holds.
  FreeInitApp app;
  app.params.rawlog = kRecordings;
  app.params.out_dir = dir("folder");
  app.params.progress = false;
  std::ostringstream log;
  try {
    app.run(log);
    ADD_FAILURE() << "ran on a folder";
  } catch (const std::exception& e) {
    EXPECT_CONTAINS(e.what(), kRecordings + ": a rosbag2 folder without metadata.yaml");
  }
}

// The progress of a recording read straight in counts its log time in seconds (a rawlog's counts
// its bytes in MB): the fixtures' 0.4 s, read to the end.
TEST(StraightIn, ProgressIsTheRecordingsLogTimeInSeconds) {
  const std::string d = dir("progress");
  const std::string ini = test::writeText(d + "/run.ini", "[window]\nduration = 0.25\n");
  for (const char* f : {"imu_cloud.mcap", "imu_cloud.db3"}) {
    FreeInitApp app;
    app.params.config_file = ini;
    app.params.rawlog = fixture(f);
    app.params.out_dir = d + "/" + f;
    app.params.echo_config = false;
    app.params.check_all = true;
    std::ostringstream log;
    app.run(log);
    EXPECT_CONTAINS(log.str(), "100%  0.4/0.4 s\n");
    EXPECT_EQ(log.str().find(" MB"), std::string::npos) << log.str();
  }
}
