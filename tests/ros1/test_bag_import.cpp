// The ROS1 bag importer against the simulator's own rawlog path: bags are written in-test with the
// rosbag C++ API from a simulator recording, imported, and compared object by object with the
// rawlog freeinit-sim writes for the same scenario; Free-Init on the import must meet the same
// accuracy. Then every kind of bad bag: each must fail with a clear error or be counted, never
// import silently wrong.
#include <freeinit/mrpt_plugins/conversions.h>
#include <freeinit/mrpt_plugins/points_map_doppler.h>
#include <freeinit/mrpt_plugins/rawlog_reader.h>
#include <freeinit/ros1/bag_writer.h>
#include <freeinit/ros1/cloud_codec.h>
#include <freeinit/sim/simulator.h>
#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/PointCloud2.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>

#include "bag_import_app.h"
#include "free_init_app.h"
#include "ros_test_files.h"
#include "sim_app.h"

using namespace freeinit;
using namespace freeinit::mrpt_plugins;
using namespace freeinit::app_support;
using namespace freeinit::apps;
namespace fs = std::filesystem;

namespace {

const std::string kSrc = FREEINIT_SOURCE_DIR;

std::string dir(const std::string& name) {
  return test::testFolder("freeinit_bag_import_tests", name);
}

// The scenario both paths record: a handheld rotational start (dyna_01), 1 s, 6000 points per
// frame (the density of the committed samples).
sim::ScenarioConfig scenario() {
  auto sc = sim::preset("dyna_01", 1);
  sc.duration = 1.0;
  sc.points_per_frame = 6000;
  return sc;
}

const sim::Recording& recording() {
  static const sim::Recording rec = sim::simulate(scenario());
  return rec;
}

// The importer INI: [bag_import] lines as given, [extrinsics] = the recording's, with 17
// significant digits so that they parse back to the same doubles.
std::string writeIni(const std::string& path, const std::string& bag_import_lines,
                     const Extrinsics& e = recording().extrinsics) {
  std::ofstream f(path);
  f << std::setprecision(17) << "[bag_import]\n" << bag_import_lines << "\n[extrinsics]\nR_bl =";
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) f << " " << e.R_bl(r, c);
  f << "\np_bl = " << e.p_bl.x() << " " << e.p_bl.y() << " " << e.p_bl.z() << "\n";
  return path;
}

BagImportApp importer(const std::string& bag, const std::string& ini, const std::string& out) {
  BagImportApp app;
  app.params.bag = bag;
  app.params.config_file = ini;
  app.params.output = out;
  app.params.progress = false;
  return app;
}

// The simulator's own rawlog of scenario(), written once by freeinit-sim's app class.
const std::string& simRawlog() {
  static const std::string path = [] {
    const std::string d = dir("sim");
    SimApp sim;
    const auto sc = scenario();
    sim.params.preset = sc.name;
    sim.params.seed = sc.seed;
    sim.params.duration = sc.duration;
    sim.params.points_per_frame = sc.points_per_frame;
    sim.params.output = d + "/dyna_01.rawlog";
    std::ostringstream log;
    sim.run(log);
    return sim.params.output;
  }();
  return path;
}

// Compares two rawlogs object by object. Time offsets may differ by `time_tol` [s] (the bag's
// resolution); everything else must be identical.
void expectSameRawlog(const std::string& expected, const std::string& actual, double time_tol) {
  const auto a = readRawlog(expected);
  const auto b = readRawlog(actual);
  ASSERT_EQ(a.size(), b.size());
  std::size_t clouds = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const auto& x = *a[i].obs;
    const auto& y = *b[i].obs;
    ASSERT_EQ(std::string(x.GetRuntimeClass()->className), y.GetRuntimeClass()->className) << i;
    ASSERT_EQ(x.sensorLabel, y.sensorLabel) << i;
    ASSERT_EQ(x.timestamp, y.timestamp) << "record " << i;
    if (const auto* imu = dynamic_cast<const mrpt::obs::CObservationIMU*>(&x)) {
      const auto& imu2 = dynamic_cast<const mrpt::obs::CObservationIMU&>(y);
      EXPECT_EQ(imu->rawMeasurements, imu2.rawMeasurements) << "record " << i;
      EXPECT_EQ(imu->dataIsPresent, imu2.dataIsPresent) << "record " << i;
      continue;
    }
    const auto& pc = dynamic_cast<const mrpt::obs::CObservationPointCloud&>(x);
    const auto& pc2 = dynamic_cast<const mrpt::obs::CObservationPointCloud&>(y);
    EXPECT_EQ(pc.sensorPose, pc2.sensorPose) << "record " << i;
    const auto& m = dynamic_cast<const CPointsMapDoppler&>(*pc.pointcloud);
    const auto& m2 = dynamic_cast<const CPointsMapDoppler&>(*pc2.pointcloud);
    ASSERT_EQ(m.size(), m2.size()) << "record " << i;
    std::size_t differ = 0;
    for (std::size_t k = 0; k < m.size(); ++k) {
      const bool same = m.getPointsBufferRef_x()[k] == m2.getPointsBufferRef_x()[k] &&
                        m.getPointsBufferRef_y()[k] == m2.getPointsBufferRef_y()[k] &&
                        m.getPointsBufferRef_z()[k] == m2.getPointsBufferRef_z()[k] &&
                        m.doppler(k) == m2.doppler(k) && m.intensity(k) == m2.intensity(k) &&
                        m.line(k) == m2.line(k) &&
                        std::abs(m.timeOffset(k) - m2.timeOffset(k)) <= time_tol;
      differ += same ? 0 : 1;
    }
    EXPECT_EQ(differ, 0u) << "record " << i;
    ++clouds;
  }
  EXPECT_EQ(clouds, recording().frames.size());
}

// Writes the recording as "<d>/<name>.bag" with `options` and imports it to "<d>/<name>.rawlog"
// with the [bag_import] `lines`.
struct Imported {
  BagImportApp app;
  std::string log;
};
Imported writeAndImport(const std::string& d, const ros1::BagWriteOptions& options,
                        const std::string& lines = "", const std::string& name = "rec") {
  ros1::writeBag(d + "/" + name + ".bag", recording().imu, recording().frames, options);
  Imported r{importer(d + "/" + name + ".bag", writeIni(d + "/" + name + ".ini", lines),
                      d + "/" + name + ".rawlog"),
             ""};
  std::ostringstream log;
  EXPECT_EQ(r.app.run(log), 0) << log.str();
  r.log = log.str();
  return r;
}

}  // namespace

// The release layout: int32 nanosecond time offsets. Clouds are recorded 0.1 s after their stamp
// (as a driver publishes a swept frame), so the importer must reorder them among the IMU messages.
// A time offset round-trips through integer nanoseconds: |error| <= 0.5 ns, plus the float32
// rounding of the result (offsets < 0.1 s: ulp 7.5e-9 s), hence 1e-8 s.
TEST(BagImport, ReleaseLayoutEqualsTheSimulatorsRawlog) {
  const std::string d = dir("release");
  const auto [app, log] = writeAndImport(d, {});
  EXPECT_EQ(app.summary.imu.imported, recording().imu.size());
  EXPECT_EQ(app.summary.lidar.imported, recording().frames.size());
  EXPECT_EQ(app.summary.imu.skipped() + app.summary.lidar.skipped(), 0u);
  EXPECT_NEAR(app.summary.imu.meanRate(), 200.0, 1e-6);
  EXPECT_EQ(app.summary.imu.gaps, 0u);
  EXPECT_TRUE(fs::is_regular_file(d + "/rec.extrinsics.ini"));
  expectSameRawlog(simRawlog(), d + "/rec.rawlog", 1e-8);
  EXPECT_NE(log.find("/imu/data (sensor_msgs/Imu): 201 messages, 201 imported"), std::string::npos)
      << log;
  // Without [bag_import] freeinit_config the defaults are suggested.
  EXPECT_NE(log.find("Run: freeinit " + d + "/rec.rawlog   (the default configuration"),
            std::string::npos)
      << log;
}

// An import INI that names the estimator's configuration for its sensor (as the radar's does):
// the importer suggests it, found beside that INI, not the defaults.
TEST(BagImport, SuggestsTheConfigurationTheImportIniNames) {
  const std::string d = dir("suggested_config");
  const auto [app, log] = writeAndImport(d, {}, "freeinit_config = ../ini/freeinit_radar.ini\n");
  EXPECT_NE(log.find("Run: freeinit " + fs::path(d).parent_path().string() +
                     "/ini/freeinit_radar.ini " + d +
                     "/rec.rawlog   (the configuration for "
                     "this sensor: [bag_import] freeinit_config of " +
                     d + "/rec.ini)"),
            std::string::npos)
      << log;
  EXPECT_EQ(log.find("the default configuration"), std::string::npos) << log;
  // The shipped radar INI names ini/freeinit_radar.ini, where docs/dataset_bags.md prescribes it.
  const auto radar = loadBagImportSettings(kSrc + "/ini/import_bag_ti_mmwave.ini");
  EXPECT_EQ(radar.freeinit_config, "freeinit_radar.ini");
  EXPECT_TRUE(fs::is_regular_file(kSrc + "/ini/" + radar.freeinit_config));
  EXPECT_EQ(loadBagImportSettings(kSrc + "/ini/import_bag.ini").freeinit_config, "");
}

// Compressed bags (rosbag record --lz4 / --bz2) read the same.
TEST(BagImport, CompressedBags) {
  const std::string d = dir("compressed");
  using C = ros1::BagWriteOptions::Compression;
  for (const C c : {C::kLz4, C::kBz2}) {
    ros1::BagWriteOptions o;
    o.compression = c;
    const std::string name = c == C::kLz4 ? "lz4" : "bz2";
    writeAndImport(d, o, "", name);
    expectSameRawlog(simRawlog(), d + "/" + name + ".rawlog", 1e-8);
  }
}

// Another layout by configuration: time as float32 seconds, big-endian data, the IMU in g, other
// topic and field names, no line field. Float seconds carry the simulator's values exactly: the
// rawlog must be identical (IMU values too: x / 9.81 * 9.81 is exact for these samples or off by
// one ulp, see below).
TEST(BagImport, ConfiguredLayoutBigEndianFloatSecondsImuInG) {
  const std::string d = dir("configured");
  ros1::BagWriteOptions o;
  o.config.imu_topic = "/xsens/imu";
  o.config.lidar_topic = "/lidar/points";
  o.config.cloud.doppler.name = "radial_vel";
  o.config.cloud.time.field = {"t", ros1::FieldType::kFloat32};
  o.config.cloud.time.scale = 1.0;
  o.big_endian = true;
  o.reflectivity = false;
  const std::string lines =
      "imu_topic = /xsens/imu\nlidar_topic = /lidar/points\ndoppler_field = radial_vel\n"
      "time_field = t\ntime_field_type = float32\ntime_scale = 1\n";
  writeAndImport(d, o, lines);
  expectSameRawlog(simRawlog(), d + "/rec.rawlog", 0.0);

  // The same bag with the IMU written in g and declared so: accelerations scaled back.
  o.config.imu_accel_in_g = true;
  writeAndImport(d, o, lines + "imu_accel_unit = g\n", "g");
  const auto recs = readRawlog(d + "/g.rawlog");
  std::size_t k = 0;
  for (const auto& r : recs) {
    const auto* imu = dynamic_cast<const mrpt::obs::CObservationIMU*>(r.obs.get());
    if (!imu) continue;
    const ImuSample s = imuFromObservation(*imu);
    // (a / 9.81) * 9.81 differs from a by at most 2 ulp.
    EXPECT_LT((s.accel - recording().imu[k].accel).cwiseAbs().maxCoeff(), 1e-14) << k;
    EXPECT_EQ(s.gyro, recording().imu[k].gyro) << k;
    ++k;
  }
  EXPECT_EQ(k, recording().imu.size());
}

// Free-Init on the import meets the bounds of the accuracy tests for a rotational start
// (test_free_init_accuracy.cpp: body velocity <= 0.05 m/s, gravity <= 0.5 deg), and gives the
// same state as on the simulator's rawlog: the inputs differ only by the sub-nanosecond time
// offset rounding of the bag format, so the states agree to far better than their errors.
TEST(BagImport, FreeInitOnTheImportMeetsTheSameAccuracy) {
  const std::string d = dir("accuracy");
  writeAndImport(d, {});
  std::ostringstream log;
  fs::copy_file(truthPathFor(simRawlog()), truthPathFor(d + "/rec.rawlog"));
  // The defaults of ini/freeinit.ini, without the PNG snapshots.
  {
    std::ofstream f(d + "/freeinit.ini");
    f << "[extrinsics]\nfrom_sensor_pose = true\n[output]\nsnapshots = false\n";
  }
  auto run = [&](const std::string& rawlog, const std::string& out) {
    FreeInitApp app;
    app.params.config_file = d + "/freeinit.ini";
    app.params.rawlog = rawlog;
    app.params.out_dir = out;
    app.params.progress = false;
    EXPECT_EQ(app.run(log), 0) << log.str();
    return app;
  };
  const FreeInitApp on_import = run(d + "/rec.rawlog", d + "/out_import");
  const FreeInitApp on_sim = run(simRawlog(), d + "/out_sim");
  ASSERT_TRUE(on_import.errors_wrt_gt && on_sim.errors_wrt_gt) << log.str();
  EXPECT_LE(on_import.errors_wrt_gt->velocity, 0.05) << log.str();
  EXPECT_LE(on_import.errors_wrt_gt->gravity_deg, 0.5) << log.str();
  const auto& a = on_import.result.state;
  const auto& b = on_sim.result.state;
  EXPECT_EQ(a.timestamp, b.timestamp);
  EXPECT_LT((a.v_w - b.v_w).norm(), 1e-3);
  EXPECT_LT((a.g_w - b.g_w).norm(), 1e-3);
  EXPECT_LT((a.b_a - b.b_a).norm(), 1e-3);
}

// ---------------------------------------------------------------------------------------------
// Bad bags. Each is written by hand with the rosbag API from the first 0.6 s of the recording.
namespace {

struct HandBag {
  std::vector<std::pair<double, sensor_msgs::Imu>> imu;  // (bag time, message)
  std::vector<std::pair<double, sensor_msgs::PointCloud2>> clouds;
  std::string imu_topic = "/imu/data";
  std::string lidar_topic = "/aeva/AeriesII/point_cloud_frame";
};

sensor_msgs::Imu imuMsg(const ImuSample& s) {
  sensor_msgs::Imu m;
  m.header.stamp = ros::Time(s.t);
  m.angular_velocity.x = s.gyro.x();
  m.angular_velocity.y = s.gyro.y();
  m.angular_velocity.z = s.gyro.z();
  m.linear_acceleration.x = s.accel.x();
  m.linear_acceleration.y = s.accel.y();
  m.linear_acceleration.z = s.accel.z();
  return m;
}

HandBag firstSeconds(double seconds = 0.6) {
  HandBag b;
  const double t_end = recording().imu.front().t + seconds;
  for (const auto& s : recording().imu)
    if (s.t < t_end) b.imu.emplace_back(s.t, imuMsg(s));
  for (const auto& f : recording().frames) {
    if (f.stamp >= t_end) break;
    sensor_msgs::PointCloud2 m;
    ros1::encodeCloud(f, ros1::CloudLayout(), true, false, m);
    b.clouds.emplace_back(f.stamp + 0.1, m);
  }
  return b;
}

void write(const HandBag& h, const std::string& path) {
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  for (const auto& [t, m] : h.imu) bag.write(h.imu_topic, ros::Time(t), m);
  for (const auto& [t, m] : h.clouds) bag.write(h.lidar_topic, ros::Time(t), m);
}

// Imports `h` with the [bag_import] lines; returns the error message ("" when it succeeded) and
// checks that a failed import left no output.
std::string importError(const HandBag& h, const std::string& name, const std::string& lines = "",
                        BagImportApp* done = nullptr) {
  const std::string d = dir(name);
  write(h, d + "/bad.bag");
  auto app = importer(d + "/bad.bag", writeIni(d + "/import.ini", lines), d + "/bad.rawlog");
  std::ostringstream log;
  try {
    app.run(log);
  } catch (const std::exception& e) {
    EXPECT_FALSE(fs::exists(d + "/bad.rawlog")) << name;
    EXPECT_FALSE(fs::exists(d + "/bad.rawlog.tmp")) << name;
    EXPECT_FALSE(fs::exists(d + "/bad.extrinsics.ini")) << name;
    return e.what();
  }
  EXPECT_TRUE(fs::is_regular_file(d + "/bad.rawlog")) << name;
  if (done) *done = app;
  return "";
}

}  // namespace

// A valid bag librosbag wrote without a message: not corrupt, it holds no messages.
TEST(BagImportBadBags, AnEmptyBagSaysItHoldsNoMessages) {
  const std::string e = importError(HandBag{}, "empty");
  EXPECT_CONTAINS(e, "bad.bag: the bag holds no messages (a valid bag");
  EXPECT_EQ(e.find("corrupt"), std::string::npos) << e;
}

TEST(BagImportBadBags, MissingTopicListsWhatTheBagHas) {
  HandBag h = firstSeconds();
  h.lidar_topic = "/aeva/other";
  const std::string e = importError(h, "missing_topic");
  EXPECT_CONTAINS(e, "no message on topic /aeva/AeriesII/point_cloud_frame (set lidar_topic)");
  EXPECT_CONTAINS(e, "/aeva/other (sensor_msgs/PointCloud2, 6 messages)");
}

TEST(BagImportBadBags, TopicOfAnotherMessageType) {
  HandBag h = firstSeconds();
  h.imu_topic = "/aeva/AeriesII/point_cloud_frame";
  h.lidar_topic = "/imu/data";
  const std::string e = importError(h, "wrong_type");
  EXPECT_CONTAINS(e, "has type sensor_msgs/");
}

TEST(BagImportBadBags, MissingAndMistypedFields) {
  HandBag h = firstSeconds();
  for (auto& [t, m] : h.clouds)
    for (auto& f : m.fields)
      if (f.name == "velocity") f.name = "doppler";
  std::string e = importError(h, "missing_field");
  EXPECT_CONTAINS(e,
                  "point_cloud_frame message 0: no field 'velocity' (Doppler velocity, set "
                  "doppler_field)");
  EXPECT_CONTAINS(e, "doppler float32");
  // The same bag with the field configured by name imports.
  EXPECT_EQ(importError(h, "missing_field_configured", "doppler_field = doppler"), "");

  h = firstSeconds();
  for (auto& [t, m] : h.clouds)
    for (auto& f : m.fields)
      if (f.name == "time_offset_ns") f.datatype = sensor_msgs::PointField::FLOAT32;
  e = importError(h, "mistyped_field");
  EXPECT_CONTAINS(e,
                  "field 'time_offset_ns' (point time) is float32, the configuration says int32");
}

TEST(BagImportBadBags, TruncatedCloudData) {
  HandBag h = firstSeconds();
  h.clouds[2].second.data.resize(h.clouds[2].second.data.size() / 2);
  EXPECT_CONTAINS(importError(h, "short_data"), "message 2: data holds");
}

// Organized, non-dense clouds mark missing returns with NaN: dropped and counted by default;
// with drop_invalid_points = false they are an error.
TEST(BagImportBadBags, NonDenseCloudsWithNaN) {
  HandBag h = firstSeconds();
  std::size_t nan_points = 0;
  for (auto& [t, m] : h.clouds) {
    m.is_dense = false;
    for (std::size_t i = 0; i < m.width; i += 10) {
      const float nan = std::numeric_limits<float>::quiet_NaN();
      std::memcpy(&m.data[i * m.point_step], &nan, sizeof(float));  // x
      ++nan_points;
    }
  }
  BagImportApp app;
  EXPECT_EQ(importError(h, "nan_dropped", "", &app), "");
  EXPECT_EQ(app.summary.invalid_points, nan_points);
  std::size_t total = 0;
  for (const auto& [t, m] : h.clouds) total += m.width;
  EXPECT_EQ(app.summary.points, total - nan_points);
  EXPECT_CONTAINS(importError(h, "nan_error", "drop_invalid_points = false"),
                  "NaN or infinite coordinate");
}

// Stamps going backwards or repeated within a topic are skipped and counted; the rawlog's stamps
// then increase strictly, and the largest gap is reported.
TEST(BagImportBadBags, OutOfOrderAndDuplicatedStampsAreCountedSkips) {
  HandBag h = firstSeconds();
  h.imu[50].second.header.stamp = h.imu[40].second.header.stamp;  // backwards
  h.imu[51].second.header.stamp = h.imu[52].second.header.stamp;  // 52 becomes a duplicate
  h.imu.erase(h.imu.begin() + 80, h.imu.begin() + 90);            // a 55 ms gap
  BagImportApp app;
  ASSERT_EQ(importError(h, "order", "", &app), "");
  EXPECT_EQ(app.summary.imu.out_of_order, 1u);
  EXPECT_EQ(app.summary.imu.duplicated, 1u);
  EXPECT_EQ(app.summary.imu.imported, h.imu.size() - 2);
  EXPECT_EQ(app.summary.imu.gaps, 2u);  // the erased stretch, and 49 -> 51 around the bad one
  EXPECT_NEAR(app.summary.imu.largest_gap, 0.055, 1e-6);
  double last = 0;
  for (const auto& r : readRawlog(app.rawlog_written)) {
    if (!dynamic_cast<const mrpt::obs::CObservationIMU*>(r.obs.get())) continue;
    const double t = toUnix(r.obs->timestamp);
    EXPECT_GT(t, last);
    last = t;
  }
}

// Clouds recorded later than the reorder window after newer IMU messages cannot be put in order.
// (A cloud late only within its own topic is an out-of-order skip, counted.)
TEST(BagImportBadBags, MessageLaterThanTheReorderWindow) {
  HandBag h = firstSeconds();
  for (auto& [t, m] : h.clouds) t += 0.4;  // recorded 0.5 s after their stamps
  EXPECT_CONTAINS(importError(h, "late", "reorder_window = 0.2"),
                  "arrived more than reorder_window = 0.200 s late; increase reorder_window");
  EXPECT_EQ(importError(h, "late_ok", "reorder_window = 0.6"), "");
}

TEST(BagImportBadBags, AccelerationUnitMismatch) {
  HandBag h = firstSeconds();
  for (auto& [t, m] : h.imu) {
    m.linear_acceleration.x /= kGravity;
    m.linear_acceleration.y /= kGravity;
    m.linear_acceleration.z /= kGravity;
  }
  EXPECT_CONTAINS(importError(h, "in_g"), "the IMU reports g, not m/s^2 (set imu_accel_unit = g)");
  EXPECT_EQ(importError(h, "in_g_declared", "imu_accel_unit = g"), "");
  EXPECT_CONTAINS(importError(firstSeconds(), "not_g", "imu_accel_unit = g"),
                  "the IMU reports m/s^2");
}

TEST(BagImportBadBags, ImuWithoutAccelerometer) {
  HandBag h = firstSeconds();
  h.imu[3].second.linear_acceleration_covariance[0] = -1;
  EXPECT_CONTAINS(importError(h, "no_accel"),
                  "/imu/data message 3: the IMU declares no linear acceleration");
}

TEST(BagImportBadBags, TruncatedBagFile) {
  const std::string d = dir("truncated");
  ros1::writeBag(d + "/rec.bag", recording().imu, recording().frames, {});
  fs::resize_file(d + "/rec.bag", fs::file_size(d + "/rec.bag") / 2);
  auto app = importer(d + "/rec.bag", writeIni(d + "/import.ini", ""), d + "/rec.rawlog");
  std::ostringstream log;
  EXPECT_THROW(app.run(log), ros1::BagError);
  EXPECT_FALSE(fs::exists(d + "/rec.rawlog"));
  EXPECT_FALSE(fs::exists(d + "/rec.rawlog.tmp"));

  auto missing = importer(d + "/nope.bag", d + "/import.ini", d + "/rec.rawlog");
  EXPECT_THROW(missing.run(log), ros1::BagError);
}

// The Doppler mode is declared; ego-compensated Doppler cannot initialize Free-Init and is refused.
TEST(BagImportBadBags, DopplerModeIsDeclaredAndEgoCompensatedIsRefused) {
  const std::string e = importError(firstSeconds(), "ego", "doppler_mode = ego_compensated");
  EXPECT_CONTAINS(e, "doppler_mode = ego_compensated: Free-Init needs the raw (relative) Doppler");
  EXPECT_CONTAINS(importError(firstSeconds(), "mode_typo", "doppler_mode = absolute"),
                  "'absolute' is not one of 'relative', 'ego_compensated'");
}

TEST(BagImportConfig, TyposAndBadValuesNameTheKey) {
  EXPECT_CONTAINS(importError(firstSeconds(), "typo", "imu_topik = /imu"),
                  "[bag_import] imu_topik: unknown key");
  EXPECT_CONTAINS(importError(firstSeconds(), "bad_type", "time_field_type = int64"),
                  "[bag_import] time_field_type: unknown field type 'int64'");
  EXPECT_CONTAINS(importError(firstSeconds(), "bad_abs", "time_relative = false"),
                  "time_relative: false (absolute UNIX times) needs time_field_type = float64");
}

// A LiDAR-IMU time offset moves every cloud stamp (and only those) by the offset.
TEST(BagImport, LidarTimeOffsetIsApplied) {
  BagImportApp app;
  ASSERT_EQ(importError(firstSeconds(), "offset", "lidar_time_offset = -0.0125", &app), "");
  std::vector<double> clouds;
  for (const auto& r : readRawlog(app.rawlog_written))
    if (dynamic_cast<const mrpt::obs::CObservationPointCloud*>(r.obs.get()))
      clouds.push_back(toUnix(r.obs->timestamp));
  ASSERT_EQ(clouds.size(), 6u);
  for (std::size_t k = 0; k < clouds.size(); ++k)
    EXPECT_NEAR(clouds[k], recording().frames[k].stamp - 0.0125, 2e-7);  // mrpt::Clock: 100 ns
}

// The shipped INI files load, with the release's layout and extrinsics.
TEST(BagImportConfig, ShippedIniFiles) {
  const auto s = loadBagImportSettings(kSrc + "/ini/import_bag.ini");
  const ros1::BagImportConfig defaults;
  EXPECT_EQ(s.bag.imu_topic, "/imu/data");
  EXPECT_EQ(s.bag.lidar_topic, "/aeva/AeriesII/point_cloud_frame");
  EXPECT_EQ(s.bag.cloud.time.field.name, "time_offset_ns");
  EXPECT_EQ(s.bag.cloud.time.field.type, ros1::FieldType::kInt32);
  EXPECT_EQ(s.bag.cloud.time.scale, 1e-9);
  EXPECT_EQ(s.bag.cloud.doppler.name, "velocity");
  EXPECT_EQ(s.bag.cloud.line.type, ros1::FieldType::kUint8);
  EXPECT_EQ(s.bag.doppler_mode, ros1::DopplerMode::kRelative);
  EXPECT_FALSE(s.bag.imu_accel_in_g);
  EXPECT_EQ(s.extrinsics.R_bl, Mat3::Identity());
  EXPECT_EQ(s.extrinsics.p_bl, Vec3(0.018, 0.0, -0.0434));
  const auto v = loadBagImportSettings(kSrc + "/ini/import_bag_vehicular.ini");
  EXPECT_EQ(v.bag.cloud.time.field.name, defaults.cloud.time.field.name);
  EXPECT_EQ(v.extrinsics.p_bl, Vec3(0.017, -0.002, -0.052));
}

// Optional fields can be left out: intensity and line are then 0.
TEST(BagImportConfig, OptionalFieldsMayBeAbsent) {
  HandBag h = firstSeconds();
  for (auto& [t, m] : h.clouds)
    for (auto& f : m.fields)
      if (f.name == "line_index" || f.name == "intensity") f.name = "unused_" + f.name;
  EXPECT_CONTAINS(importError(h, "no_line"),
                  "no field 'intensity' (intensity, set intensity_field)");
  BagImportApp app;
  ASSERT_EQ(importError(h, "no_line_ok", "intensity_field =\nline_field =", &app), "");
  for (const auto& r : readRawlog(app.rawlog_written))
    if (const auto* pc = dynamic_cast<const mrpt::obs::CObservationPointCloud*>(r.obs.get())) {
      const LidarFrame f = frameFromObservation(*pc);
      EXPECT_EQ(f.points[7].line, 0);
      EXPECT_EQ(f.points[7].intensity, 0.0f);
    }
}

// Absolute per-point times (float64 UNIX seconds, time_relative = false) give the same offsets to
// within the resolution of a double at 1.7e9 s (2.4e-7 s; 5e-7 s allowed).
TEST(BagImport, AbsoluteFloat64PointTimes) {
  const std::string d = dir("absolute");
  ros1::BagWriteOptions o;
  o.config.cloud.time = {{"timestamp", ros1::FieldType::kFloat64}, 1.0, false};
  writeAndImport(d, o,
                 "time_field = timestamp\ntime_field_type = float64\ntime_scale = 1\n"
                 "time_relative = false\n");
  expectSameRawlog(simRawlog(), d + "/rec.rawlog", 5e-7);
}

// Organized clouds (height > 1) with padding at the end of each row read row by row.
TEST(BagImport, OrganizedCloudsWithRowPadding) {
  HandBag h = firstSeconds();
  std::vector<LidarFrame> expected;
  for (auto& [t, m] : h.clouds) {
    expected.push_back(ros1::decodeCloud(m, ros1::CloudLayout(), false));
    const std::size_t rows = 2, width = m.width / rows, pad = 12;
    std::vector<std::uint8_t> data;
    for (std::size_t r = 0; r < rows; ++r) {
      const auto* row = m.data.data() + r * width * m.point_step;
      data.insert(data.end(), row, row + width * m.point_step);
      data.insert(data.end(), pad, 0xAB);
    }
    m.height = rows;
    m.width = static_cast<std::uint32_t>(width);
    m.row_step = static_cast<std::uint32_t>(width * m.point_step + pad);
    m.data = data;
    expected.back().points.resize(rows * width);  // an odd last point is not in the new layout
  }
  BagImportApp app;
  ASSERT_EQ(importError(h, "organized", "", &app), "");
  std::size_t k = 0;
  for (const auto& r : readRawlog(app.rawlog_written)) {
    const auto* pc = dynamic_cast<const mrpt::obs::CObservationPointCloud*>(r.obs.get());
    if (!pc) continue;
    const LidarFrame f = frameFromObservation(*pc);
    ASSERT_EQ(f.points.size(), expected[k].points.size());
    for (std::size_t i = 0; i < f.points.size(); ++i)
      ASSERT_EQ(f.points[i].p_l, expected[k].points[i].p_l) << k << " " << i;
    ++k;
  }
  EXPECT_EQ(k, h.clouds.size());
}
