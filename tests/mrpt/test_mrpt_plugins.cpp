// Unit tests of the MRPT glue: the Doppler map's serialization, conversions, the streaming rawlog
// reader (truncation, unregistered classes) and its seek index, and the record checks of the
// ingest path on whole recordings (INI loading: tests/config).
#include <freeinit/app_support/app_config.h>
#include <freeinit/app_support/checked_recording.h>
#include <freeinit/app_support/ingest.h>
#include <freeinit/app_support/output_writers.h>
#include <freeinit/mrpt_plugins/conversions.h>
#include <freeinit/mrpt_plugins/points_map_doppler.h>
#include <freeinit/mrpt_plugins/rawlog_reader.h>
#include <freeinit/mrpt_plugins/rawlog_writer.h>
#include <freeinit/mrpt_plugins/register.h>
#include <gtest/gtest.h>
#include <mrpt/config/CConfigFile.h>
#include <mrpt/io/CFileOutputStream.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/serialization/CArchive.h>
#include <sys/resource.h>
#include <sys/stat.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <random>
#include <sstream>

using namespace freeinit;
using namespace freeinit::mrpt_plugins;
using namespace freeinit::app_support;
namespace fs = std::filesystem;

namespace {

std::string tmpPath(const std::string& name) {
  const auto dir = fs::temp_directory_path() / "freeinit_mrpt_tests";
  fs::create_directories(dir);
  return (dir / name).string();
}

LidarFrame randomFrame(double stamp, std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-20.f, 20.f);
  LidarFrame f;
  f.stamp = stamp;
  for (std::size_t i = 0; i < n; ++i) {
    DopplerPoint p;
    p.p_l = Eigen::Vector3f(u(rng) + 30.f, u(rng), 0.2f * u(rng));
    p.doppler = 0.1f * u(rng);
    p.time_offset = 0.1f * static_cast<float>(i) / static_cast<float>(n);
    p.intensity = 0.5f + 0.01f * u(rng);
    p.line = static_cast<std::uint16_t>(i % 64);
    f.points.push_back(p);
  }
  return f;
}

Extrinsics someExtrinsics() {
  Extrinsics e;
  e.R_bl = Eigen::AngleAxisd(0.05, Vec3(0.2, -0.3, 1).normalized()).toRotationMatrix();
  e.p_bl = Vec3(0.1, -0.05, 0.12);
  return e;
}

// A consistent recording: 200 Hz IMU at rest (1 g up), 10 Hz frames, `seconds` long.
std::vector<RawlogRecord> goodRecords(double seconds = 1.0) {
  std::vector<RawlogRecord> r;
  std::size_t idx = 0;
  const double t0 = 1700000000.0;
  for (int i = 0; i <= static_cast<int>(seconds * 200); ++i) {
    const double t = t0 + i * 0.005;
    if (i % 20 == 0)
      r.push_back({idx++, frameToObservation(randomFrame(t, 200, static_cast<unsigned>(i)),
                                             someExtrinsics(), "LIDAR")});
    ImuSample s;
    s.t = t;
    s.accel = Vec3(0, 0, kGravity);
    r.push_back({idx++, imuToObservation(s, "IMU")});
  }
  return r;
}

AppConfig sensorPoseConfig() {
  return loadAppConfigFromText("[extrinsics]\nfrom_sensor_pose = true\n", "test.ini");
}

void expectThrowsWith(const std::function<void()>& f, const std::string& needle) {
  try {
    f();
    ADD_FAILURE() << "no exception; expected one mentioning '" << needle << "'";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos)
        << "message: " << e.what() << "\nexpected to contain: " << needle;
  }
}

void writeRawlogPlain(const std::string& path, const std::vector<RawlogRecord>& records) {
  mrpt::io::CFileOutputStream f(path);
  auto a = mrpt::serialization::archiveFrom(f);
  for (const auto& r : records) a << *r.obs;
}

void writeRawlogGz(const std::string& path, const std::vector<RawlogRecord>& records) {
  RawlogWriter w(path);
  for (const auto& r : records) w.write(*r.obs);
  w.commit();
}

// The records as a rawlog file, read back by the ingest path (readRecording).
CheckedRecording validate(const std::vector<RawlogRecord>& records, const AppConfig& config,
                          const std::string& name = "bad.rawlog") {
  const std::string p = tmpPath(name);
  writeRawlogPlain(p, records);
  return readRecording(p, config);
}

// The IMU of goodRecords turning: a gyro that varies by 0.5 rad/s.
void makeImuTurn(std::vector<RawlogRecord>& r) {
  int k = 0;
  for (auto& x : r)
    if (auto imu = std::dynamic_pointer_cast<mrpt::obs::CObservationIMU>(x.obs))
      imu->set(mrpt::obs::IMU_WZ, 0.5 * std::sin(0.2 * k++));
}

}  // namespace

TEST(DopplerMap, SerializationRoundTripKeepsEveryField) {
  registerClasses();
  const LidarFrame f = randomFrame(1700000000.25, 1000, 7);
  auto obs = frameToObservation(f, someExtrinsics(), "LIDAR");

  mrpt::io::CMemoryStream buf;
  auto out = mrpt::serialization::archiveFrom(buf);
  out << *obs->pointcloud;
  buf.Seek(0);
  auto in = mrpt::serialization::archiveFrom(buf);
  auto obj = in.ReadObject();
  auto map = std::dynamic_pointer_cast<CPointsMapDoppler>(obj);
  ASSERT_TRUE(map);
  ASSERT_EQ(map->size(), f.points.size());
  for (std::size_t i = 0; i < f.points.size(); ++i) {
    float x, y, z;
    map->getPoint(i, x, y, z);
    EXPECT_EQ(x, f.points[i].p_l.x());
    EXPECT_EQ(z, f.points[i].p_l.z());
    EXPECT_EQ(map->doppler(i), f.points[i].doppler);
    EXPECT_EQ(map->timeOffset(i), f.points[i].time_offset);
    EXPECT_EQ(map->intensity(i), f.points[i].intensity);
    EXPECT_EQ(map->line(i), f.points[i].line);
  }
}

// A rawlog names each object by its class with its namespace; files written while the layer's
// namespace was freeinit::mrpt_glue must still read (the user's recordings outlive the rename).
TEST(DopplerMap, RecordingsWithTheEarlierClassNameStillRead) {
  registerClasses();
  const LidarFrame f = randomFrame(1700000000.25, 50, 3);
  auto obs = frameToObservation(f, someExtrinsics(), "LIDAR");
  mrpt::io::CMemoryStream buf;
  auto out = mrpt::serialization::archiveFrom(buf);
  out << *obs->pointcloud;
  const auto* data = static_cast<const char*>(buf.getRawBufferData());
  std::string bytes(data, data + buf.getTotalBytesCount());

  // The archive stores the name as one length byte followed by its characters.
  const std::string current = CLASS_ID(CPointsMapDoppler)->className;
  const std::string legacy = kLegacyPointsMapDopplerName;
  const auto at = bytes.find(current);
  ASSERT_NE(at, std::string::npos);
  ASSERT_GT(at, 0u);
  const auto length_byte = static_cast<unsigned char>(bytes[at - 1]);
  ASSERT_EQ(length_byte & 0x7F, current.size());
  bytes.replace(at, current.size(), legacy);
  bytes[at - 1] = static_cast<char>((length_byte & 0x80) | legacy.size());

  mrpt::io::CMemoryStream old_file;
  old_file.assignMemoryNotOwn(bytes.data(), bytes.size());
  auto in = mrpt::serialization::archiveFrom(old_file);
  auto map = std::dynamic_pointer_cast<CPointsMapDoppler>(in.ReadObject());
  ASSERT_TRUE(map);
  ASSERT_EQ(map->size(), f.points.size());
  EXPECT_EQ(map->doppler(7), f.points[7].doppler);
}

TEST(DopplerMap, ObservationRoundTripThroughStockCObservationPointCloud) {
  registerClasses();
  const LidarFrame f = randomFrame(1700000000.25, 500, 3);
  const Extrinsics e = someExtrinsics();
  auto obs = frameToObservation(f, e, "LIDAR");
  EXPECT_EQ(std::string(obs->GetRuntimeClass()->className), "mrpt::obs::CObservationPointCloud");

  mrpt::io::CMemoryStream buf;
  auto out = mrpt::serialization::archiveFrom(buf);
  out << *obs;
  buf.Seek(0);
  auto in = mrpt::serialization::archiveFrom(buf);
  auto back = std::dynamic_pointer_cast<mrpt::obs::CObservationPointCloud>(in.ReadObject());
  ASSERT_TRUE(back);
  EXPECT_EQ(back->sensorLabel, "LIDAR");
  const LidarFrame g = frameFromObservation(*back);
  EXPECT_NEAR(g.stamp, f.stamp, 1e-6);  // mrpt::Clock has 100 ns ticks
  ASSERT_EQ(g.points.size(), f.points.size());
  for (std::size_t i = 0; i < f.points.size(); ++i) {
    EXPECT_EQ(g.points[i].p_l, f.points[i].p_l);
    EXPECT_EQ(g.points[i].doppler, f.points[i].doppler);
    EXPECT_EQ(g.points[i].line, f.points[i].line);
  }
  const Extrinsics e2 = extrinsicsFromPose(back->sensorPose);
  EXPECT_LT((e2.R_bl - e.R_bl).norm(), 1e-12);
  EXPECT_LT((e2.p_bl - e.p_bl).norm(), 1e-12);
}

TEST(DopplerMap, CopyAndInsertAnotherMapKeepExtraFields) {
  const LidarFrame f = randomFrame(0, 50, 1);
  auto obs = frameToObservation(f, Extrinsics(), "L");
  const auto& src = dynamic_cast<const CPointsMapDoppler&>(*obs->pointcloud);
  CPointsMapDoppler copy(src);
  ASSERT_EQ(copy.size(), 50u);
  EXPECT_EQ(copy.doppler(10), f.points[10].doppler);
  copy.insertAnotherMap(&src, mrpt::poses::CPose3D());
  ASSERT_EQ(copy.size(), 100u);
  EXPECT_EQ(copy.doppler(60), f.points[10].doppler);
  EXPECT_EQ(copy.line(60), f.points[10].line);
}

TEST(Conversions, ImuGyroIndicesAreZYXInMrpt258) {
  mrpt::obs::CObservationIMU obs;
  obs.timestamp = fromUnix(1700000000.5);
  // Raw indices as MRPT 2.5.8 defines them: 0..2 accel x, y, z; 3 = wz (yaw), 4 = wy, 5 = wx.
  const double raw[6] = {1.0, 2.0, 3.0, 0.3, 0.2, 0.1};
  for (int i = 0; i < 6; ++i) {
    obs.rawMeasurements[static_cast<std::size_t>(i)] = raw[i];
    obs.dataIsPresent[static_cast<std::size_t>(i)] = true;
  }
  const ImuSample s = imuFromObservation(obs);
  EXPECT_EQ(s.gyro, Vec3(0.1, 0.2, 0.3));
  EXPECT_EQ(s.accel, Vec3(1.0, 2.0, 3.0));
  EXPECT_NEAR(s.t, 1700000000.5, 1e-6);

  auto back = imuToObservation(s, "IMU");
  EXPECT_EQ(back->rawMeasurements[3], 0.3);  // wz
  EXPECT_EQ(back->rawMeasurements[5], 0.1);  // wx
  EXPECT_EQ(imuFromObservation(*back, kGravity).accel, kGravity * s.accel);

  mrpt::obs::CObservationIMU missing;
  missing.set(mrpt::obs::IMU_WZ, 1.0);
  EXPECT_THROW(imuFromObservation(missing), std::invalid_argument);
}

TEST(Conversions, ClockRoundTripAt100ns) {
  for (double t : {0.0, 1700000000.123456, 1234567890.5}) EXPECT_NEAR(toUnix(fromUnix(t)), t, 2e-7);
}

TEST(RawlogReader, ReadsAWholeFile) {
  const auto recs = goodRecords();
  const std::string p = tmpPath("good.rawlog");
  writeRawlogPlain(p, recs);
  const auto back = readRawlog(p);
  ASSERT_EQ(back.size(), recs.size());
  EXPECT_EQ(back.back().index, recs.size() - 1);
}

TEST(RawlogReader, MissingAndEmptyFilesFailLoudly) {
  expectThrowsWith([] { readRawlog(tmpPath("does_not_exist.rawlog")); }, "file not found");
  const std::string p = tmpPath("empty.rawlog");
  std::ofstream(p).close();
  expectThrowsWith([&] { readRawlog(p); }, "empty file");
}

TEST(RawlogReader, TruncatedFileFailsNamingTheRecord) {
  const auto recs = goodRecords();
  const std::string p = tmpPath("truncated.rawlog");
  writeRawlogPlain(p, recs);
  fs::resize_file(p, fs::file_size(p) * 2 / 3);
  try {
    readRawlog(p);
    FAIL() << "a truncated rawlog was accepted";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find(p), std::string::npos) << m;
    EXPECT_NE(m.find("record "), std::string::npos) << m;
    EXPECT_NE(m.find("truncated"), std::string::npos) << m;
  }
}

TEST(RawlogReader, UnregisteredClassFailsInsteadOfTruncatingSilently) {
  // Rename the serialized class of the point cloud to one nobody registered (same length).
  const auto recs = goodRecords();
  mrpt::io::CMemoryStream buf;
  auto a = mrpt::serialization::archiveFrom(buf);
  for (const auto& r : recs) a << *r.obs;
  std::string bytes(static_cast<const char*>(buf.getRawBufferData()), buf.getTotalBytesCount());
  const std::string from = "CPointsMapDoppler", to = "CPointsMapDopplez";
  std::size_t replaced = 0;
  for (auto pos = bytes.find(from); pos != std::string::npos; pos = bytes.find(from, pos + 1)) {
    bytes.replace(pos, from.size(), to);
    ++replaced;
  }
  ASSERT_GT(replaced, 0u);
  const std::string p = tmpPath("unregistered.rawlog");
  std::ofstream(p, std::ios::binary)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  expectThrowsWith([&] { readRawlog(p); }, "record 0");
  expectThrowsWith([&] { readRawlog(p); }, "not registered");
}

TEST(InputValidator, AcceptsAConsistentRecording) {
  const auto in = validate(goodRecords(), sensorPoseConfig(), "x.rawlog");
  EXPECT_EQ(in.imu.size(), 201u);
  EXPECT_EQ(in.frames.size(), 11u);
  ASSERT_TRUE(in.sensor_pose_extrinsics);
  EXPECT_LT((in.sensor_pose_extrinsics->p_bl - someExtrinsics().p_bl).norm(), 1e-12);
}

TEST(InputValidator, RejectsEachKindOfBadInput) {
  const AppConfig cfg = sensorPoseConfig();
  auto check = [&](std::vector<RawlogRecord> recs, const std::string& needle, const AppConfig& c) {
    expectThrowsWith([&] { validate(recs, c); }, needle);
  };
  auto imuAt = [](std::vector<RawlogRecord>& r, std::size_t k) {
    for (std::size_t i = k; i < r.size(); ++i)
      if (IS_CLASS(*r[i].obs, mrpt::obs::CObservationIMU)) return i;
    return r.size();
  };
  auto cloudAt = [](std::vector<RawlogRecord>& r, std::size_t k) {
    for (std::size_t i = k; i < r.size(); ++i)
      if (IS_CLASS(*r[i].obs, mrpt::obs::CObservationPointCloud)) return i;
    return r.size();
  };

  {  // no IMU
    auto r = goodRecords();
    r.erase(std::remove_if(
                r.begin(), r.end(),
                [](const RawlogRecord& x) { return IS_CLASS(*x.obs, mrpt::obs::CObservationIMU); }),
            r.end());
    check(r, "no CObservationIMU", cfg);
  }
  {  // a stock cloud without Doppler
    auto r = goodRecords();
    const auto k = cloudAt(r, 5);
    auto pc = mrpt::obs::CObservationPointCloud::Create();
    pc->sensorLabel = "LIDAR";
    pc->timestamp = r[k].obs->timestamp;
    auto m = mrpt::maps::CSimplePointsMap::Create();
    m->insertPoint(1, 2, 3);
    pc->pointcloud = m;
    r[k].obs = pc;
    check(r,
          "record " + std::to_string(r[k].index) +
              ": CObservationPointCloud 'LIDAR' holds a "
              "mrpt::maps::CSimplePointsMap, which has no per-point Doppler",
          cfg);
  }
  {  // IMU timestamp backwards, then duplicated
    auto r = goodRecords();
    const auto k = imuAt(r, 50);
    r[k].obs->timestamp = fromUnix(toUnix(r[k].obs->timestamp) - 0.5);
    check(r, "record " + std::to_string(r[k].index) + ": IMU timestamp goes backwards", cfg);
    auto r2 = goodRecords();
    const auto k2 = imuAt(r2, 50), k3 = imuAt(r2, k2 + 1);
    r2[k3].obs->timestamp = r2[k2].obs->timestamp;
    check(r2, "IMU timestamp duplicated", cfg);
  }
  {  // cloud timestamp duplicated
    auto r = goodRecords();
    const auto k = cloudAt(r, 0), k2 = cloudAt(r, k + 1);
    r[k2].obs->timestamp = r[k].obs->timestamp;
    check(r, "point cloud timestamp duplicated", cfg);
  }
  {  // NaN / inf points: an error, or dropped and reported when configured
    auto r = goodRecords();
    const auto k = cloudAt(r, 3);
    auto pc = std::dynamic_pointer_cast<mrpt::obs::CObservationPointCloud>(r[k].obs);
    pc->pointcloud->setPoint(3, std::numeric_limits<float>::quiet_NaN(), 0, 0);
    pc->pointcloud->setPoint(4, std::numeric_limits<float>::infinity(), 0, 0);
    check(r, "2 of 200 points have NaN or infinite", cfg);
    AppConfig drop = cfg;
    drop.input.drop_invalid_points = true;
    EXPECT_EQ(validate(r, drop).invalid_points_dropped, 2u);
  }
  {  // empty cloud
    auto r = goodRecords();
    const auto k = cloudAt(r, 3);
    r[k].obs =
        frameToObservation(LidarFrame{toUnix(r[k].obs->timestamp), {}}, someExtrinsics(), "LIDAR");
    check(r, "empty point cloud", cfg);
  }
  {  // Doppler zero everywhere while the IMU turns (at rest it is legitimate: see below)
    auto r = goodRecords();
    makeImuTurn(r);
    const auto k = cloudAt(r, 3);
    LidarFrame f = randomFrame(toUnix(r[k].obs->timestamp), 100, 1);
    for (auto& p : f.points) p.doppler = 0;
    r[k].obs = frameToObservation(f, someExtrinsics(), "LIDAR");
    check(r,
          "record " + std::to_string(k) +
              ": the Doppler field is zero for every point while the IMU shows motion",
          cfg);
  }
  {  // IMU too slow: keep one sample in 10 (20 Hz)
    auto r = goodRecords(6.0);
    std::vector<RawlogRecord> slow;
    int n = 0;
    for (auto& x : r)
      if (!IS_CLASS(*x.obs, mrpt::obs::CObservationIMU) || n++ % 10 == 0) slow.push_back(x);
    check(slow, "below [input] min_imu_rate", cfg);
  }
  {  // IMU in g, and the reverse
    auto r = goodRecords();
    for (auto& x : r)
      if (auto imu = std::dynamic_pointer_cast<mrpt::obs::CObservationIMU>(x.obs))
        imu->set(mrpt::obs::IMU_Z_ACC, 1.0);
    check(r, "set [input] imu_accel_in_g = true", cfg);
    AppConfig in_g = cfg;
    in_g.input.imu_accel_in_g = true;
    EXPECT_NO_THROW(validate(r, in_g));
    check(goodRecords(), "already in m/s^2", in_g);
  }
  {  // shorter than the window
    check(goodRecords(0.3), "recording shorter than the window", cfg);
  }
}

TEST(Writers, InitialStateIniFollowsTheContract) {
  InitialState s;
  s.status = InitStatus::Ok;
  s.timestamp = 1700000000.5;
  s.q_wb = Quat(Eigen::AngleAxisd(0.3, Vec3::UnitZ()));
  s.v_w = Vec3(1, 2, 3);
  s.cov = Cov18::Identity() * 0.01;
  const std::string p = tmpPath("initial_state.ini");
  writeInitialStateIni(p, s);
  EXPECT_FALSE(fs::exists(p + ".tmp"));
  mrpt::config::CConfigFile ini(p);
  EXPECT_EQ(ini.read_string("initial_state", "status", "", true), "ok");
  EXPECT_NEAR(ini.read_double("initial_state", "timestamp", 0, true), 1700000000.5, 1e-9);
  std::vector<double> cov;
  ini.read_vector("initial_state", "cov", std::vector<double>(), cov, true);
  ASSERT_EQ(cov.size(), 324u);
  EXPECT_DOUBLE_EQ(cov[19], 0.01);  // (1,1)
  std::vector<double> q;
  ini.read_vector("initial_state", "q_wb", std::vector<double>(), q, true);
  ASSERT_EQ(q.size(), 4u);
  EXPECT_NEAR(q[0], s.q_wb.w(), 1e-15);
  for (const char* k : {"p_w", "v_w", "b_g", "b_a", "g_w"}) {
    std::vector<double> v;
    ini.read_vector("initial_state", k, std::vector<double>(), v, true);
    EXPECT_EQ(v.size(), 3u) << k;
  }
}

TEST(Writers, AFailedWriteLeavesNoFile) {
  const std::string p = tmpPath("never.txt");
  fs::remove(p);
  EXPECT_THROW(writeFileAtomically(p, [](std::ostream&) { throw std::runtime_error("boom"); }),
               std::runtime_error);
  EXPECT_FALSE(fs::exists(p));
  EXPECT_FALSE(fs::exists(p + ".tmp"));
}

// A recording whose write fails (here the file-size limit, as a full disk does) keeps every
// whole record written before the failure and reads without error: the file is cut back to the
// end of the last whole record and its gzip stream ended there.
TEST(RawlogWriter, ARecordingWhoseWriteFailsEndsAtItsLastWholeRecord) {
  const std::string p = tmpPath("cut_recording.rawlog");
  fs::remove(p);
  const auto records = readRawlog(std::string(FREEINIT_SOURCE_DIR) + "/rawlogs/dyna_01.rawlog");
  ASSERT_GT(records.size(), 100u);
  RawlogWriter w(p);
  w.keepPartial();
  rlimit old{};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &old), 0);
  const auto previous = std::signal(SIGXFSZ, SIG_IGN);
  rlimit small = old;
  small.rlim_cur = 400 * 1024;  // [bytes] about a fifth of the sample
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &small), 0);
  bool failed = false;
  for (const auto& r : records) {
    try {
      w.write(*r.obs);
    } catch (const std::exception& e) {
      failed = true;
      EXPECT_NE(std::string(e.what()).find(std::strerror(EFBIG)), std::string::npos) << e.what();
      break;
    }
  }
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &old), 0);
  std::signal(SIGXFSZ, previous);
  ASSERT_TRUE(failed);
  EXPECT_EQ(w.error(), std::strerror(EFBIG));
  const std::size_t whole = w.records();
  EXPECT_GT(whole, 10u);
  EXPECT_LT(whole, records.size());
  EXPECT_THROW(w.commit(), std::runtime_error);  // kept, and the failure still reported
  const auto back = readRawlog(p);
  ASSERT_EQ(back.size(), whole);
  for (std::size_t i = 0; i < whole; ++i)
    EXPECT_EQ(back[i].obs->timestamp, records[i].obs->timestamp) << i;
  EXPECT_FALSE(fs::exists(p + ".tmp"));
}

// A sensor with quantized Doppler reads exactly zero at rest: frames with zero Doppler everywhere
// are accepted when the IMU around them shows rest, refused when it shows motion.
TEST(InputValidator, ZeroDopplerIsAcceptedAtRestOnly) {
  auto zeroed = [](std::vector<RawlogRecord> r) {
    for (auto& x : r)
      if (auto pc = std::dynamic_pointer_cast<mrpt::obs::CObservationPointCloud>(x.obs)) {
        LidarFrame f = frameFromObservation(*pc);
        for (auto& p : f.points) p.doppler = 0;
        x.obs = frameToObservation(f, someExtrinsics(), "LIDAR");
        x.obs->timestamp = pc->timestamp;
      }
    return r;
  };
  const auto at_rest = validate(zeroed(goodRecords()), sensorPoseConfig(), "zero_rest.rawlog");
  EXPECT_EQ(at_rest.frames.size(), 11u);
  auto turning = goodRecords();
  makeImuTurn(turning);
  expectThrowsWith([&] { validate(zeroed(turning), sensorPoseConfig(), "zero_moving.rawlog"); },
                   "record 0: the Doppler field is zero for every point while the IMU shows "
                   "motion: the gyro varies by");
  // A sensor with Doppler bins reads zero everywhere when it moves slowly: declared, accepted.
  AppConfig binned = sensorPoseConfig();
  binned.input.doppler_resolution = 0.125;
  EXPECT_EQ(validate(zeroed(turning), binned, "zero_binned.rawlog").frames.size(), 11u);
}

TEST(RawlogReader, GzipAndPlainReadTheSame) {
  const auto recs = goodRecords();
  const std::string gz = tmpPath("same.rawlog"), plain = tmpPath("same_plain.rawlog");
  writeRawlogGz(gz, recs);
  writeRawlogPlain(plain, recs);
  const auto a = readRawlog(gz), b = readRawlog(plain);
  ASSERT_EQ(a.size(), recs.size());
  ASSERT_EQ(b.size(), recs.size());
  for (std::size_t i = 0; i < recs.size(); ++i) {
    EXPECT_EQ(a[i].obs->timestamp, recs[i].obs->timestamp);
    EXPECT_EQ(b[i].obs->timestamp, recs[i].obs->timestamp);
  }
}

// A gzip file cut anywhere is an error naming the record, never a shorter valid file, even when
// the cut falls between two records.
TEST(RawlogReader, TruncatedGzipFailsNamingTheRecord) {
  const std::string p = tmpPath("cut.rawlog");
  for (const double fraction : {0.9, 0.5, 0.1}) {
    writeRawlogGz(p, goodRecords());
    fs::resize_file(p,
                    static_cast<std::uintmax_t>(static_cast<double>(fs::file_size(p)) * fraction));
    expectThrowsWith([&] { readRawlog(p); }, "truncated file");
    expectThrowsWith([&] { readRawlog(p); }, p + ": record ");
  }
  // A flipped byte inside the compressed data.
  writeRawlogGz(p, goodRecords());
  {
    std::fstream f(p, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(fs::file_size(p) / 2));
    f.put('\x5a');
    f.seekp(static_cast<std::streamoff>(fs::file_size(p) / 2 + 1));
    f.put('\xa5');
  }
  EXPECT_THROW(readRawlog(p), InputError);
}

namespace {

// A gzip rawlog of about 1.5 MB decompressed (3 s, 2000 points per cloud) and its records as a
// sequential read sees them.
struct IndexedFixture {
  std::string path;
  std::vector<std::pair<std::size_t, double>> records;  // (record, time)
  RawlogIndexPolicy policy;

  explicit IndexedFixture(const std::string& name) : path(tmpPath(name)) {
    std::vector<RawlogRecord> r;
    std::size_t idx = 0;
    for (int i = 0; i <= 600; ++i) {
      const double t = 1700000000.0 + i * 0.005;
      if (i % 20 == 0)
        r.push_back({idx++, frameToObservation(randomFrame(t, 2000, static_cast<unsigned>(i)),
                                               someExtrinsics(), "LIDAR")});
      ImuSample s;
      s.t = t;
      s.accel = Vec3(0, 0, kGravity);
      r.push_back({idx++, imuToObservation(s, "IMU")});
    }
    writeRawlogGz(path, r);
    for (const auto& x : r) records.emplace_back(x.index, toUnix(x.obs->timestamp));
    policy.min_file_bytes = 0;
    policy.spacing = 64 * 1024;
    fs::remove(indexPathBeside(path));
  }
  /// The first record at or after t, as a sequential read finds it.
  std::size_t firstAtOrAfter(double t) const {
    for (const auto& [i, ti] : records)
      if (ti >= t) return i;
    return records.size();
  }
};

}  // namespace

// The index is written beside the rawlog, covers what was read, is extended by later reads and
// lets a reader jump to any record without deserializing anything before it.
TEST(RawlogIndex, CreatedReusedExtendedAndStale) {
  IndexedFixture fx("indexed.rawlog");
  const double t0 = fx.records.front().second;
  {
    RawlogReader reader(fx.path, fx.policy);
    EXPECT_FALSE(reader.indexLoaded());
    RawlogObject rec;
    for (int i = 0; i < 100; ++i) ASSERT_TRUE(reader.next(rec));
    EXPECT_EQ(reader.saveIndex(), indexPathBeside(fx.path));
  }
  ASSERT_TRUE(fs::is_regular_file(indexPathBeside(fx.path)));
  {  // Partial: the first 100 records, then extended to the end by a jump beyond them.
    RawlogReader reader(fx.path, fx.policy);
    ASSERT_TRUE(reader.indexLoaded());
    EXPECT_EQ(reader.index().records.size(), 100u);
    EXPECT_FALSE(reader.index().complete);
    ASSERT_TRUE(reader.seekToTime(t0 + 2.0));
    RawlogObject rec;
    ASSERT_TRUE(reader.next(rec));
    EXPECT_EQ(rec.index, fx.firstAtOrAfter(t0 + 2.0));
    while (reader.next(rec)) {
    }
    EXPECT_TRUE(reader.index().complete);
    EXPECT_FALSE(reader.saveIndex().empty());
  }
  {  // Complete: every jump lands on the record a sequential read finds, deserializing only it.
    for (const double dt : {0.0, 0.37, 1.0, 1.8, 2.64, 2.999}) {
      RawlogReader reader(fx.path, fx.policy);
      ASSERT_TRUE(reader.indexLoaded());
      EXPECT_TRUE(reader.index().complete);
      EXPECT_GT(reader.index().points.size(), 10u);  // ~1.5 MB at 64 KiB spacing
      ASSERT_TRUE(reader.seekToTime(t0 + dt)) << dt;
      RawlogObject rec;
      ASSERT_TRUE(reader.next(rec));
      EXPECT_EQ(rec.index, fx.firstAtOrAfter(t0 + dt)) << dt;
      ASSERT_TRUE(rec.t);
      EXPECT_EQ(*rec.t, fx.records[rec.index].second);
      EXPECT_EQ(reader.recordsDeserialized(), 1u) << dt;
      std::size_t n = 1;
      while (reader.next(rec)) ++n;
      EXPECT_EQ(rec.index + 1, fx.records.size());
      EXPECT_EQ(n, fx.records.size() - fx.firstAtOrAfter(t0 + dt));
      EXPECT_EQ(reader.saveIndex(), "");  // nothing new
    }
    RawlogReader reader(fx.path, fx.policy);
    EXPECT_FALSE(reader.seekToTime(t0 + 10.0));  // after the last record
  }
  {  // The rawlog changes: the index is stale, ignored and rebuilt.
    const auto before = fs::last_write_time(fx.path);
    {
      std::ofstream f(fx.path, std::ios::app | std::ios::binary);
      f << "x";
    }
    fs::resize_file(fx.path, fs::file_size(fx.path) - 1);  // same bytes, newer time
    fs::last_write_time(fx.path, before + std::chrono::seconds(5));
    RawlogReader reader(fx.path, fx.policy);
    EXPECT_FALSE(reader.indexLoaded());
    ASSERT_TRUE(reader.seekToTime(t0 + 1.0));
    RawlogObject rec;
    ASSERT_TRUE(reader.next(rec));
    EXPECT_EQ(rec.index, fx.firstAtOrAfter(t0 + 1.0));
    EXPECT_FALSE(reader.saveIndex().empty());
  }
  RawlogReader again(fx.path, fx.policy);
  EXPECT_TRUE(again.indexLoaded());
}

// Plain (uncompressed) rawlogs seek by file offset; no index for small files by default.
TEST(RawlogIndex, PlainFilesAndTheSizeThreshold) {
  IndexedFixture fx("plain_indexed.rawlog");
  {
    std::vector<RawlogRecord> all = readRawlog(fx.path);
    writeRawlogPlain(fx.path, all);
  }
  {
    RawlogReader reader(fx.path, fx.policy);
    RawlogObject rec;
    while (reader.next(rec)) {
    }
    EXPECT_FALSE(reader.saveIndex().empty());
  }
  RawlogReader reader(fx.path, fx.policy);
  ASSERT_TRUE(reader.indexLoaded());
  ASSERT_TRUE(reader.seekToTime(fx.records.front().second + 1.5));
  RawlogObject rec;
  ASSERT_TRUE(reader.next(rec));
  EXPECT_EQ(rec.index, fx.firstAtOrAfter(fx.records.front().second + 1.5));
  EXPECT_EQ(reader.recordsDeserialized(), 1u);

  fs::remove(indexPathBeside(fx.path));
  RawlogReader small(fx.path);  // default policy: no index below 64 MB
  while (small.next(rec)) {
  }
  EXPECT_EQ(small.saveIndex(), "");
  EXPECT_FALSE(fs::exists(indexPathBeside(fx.path)));
}

// Whatever lies at the index's path is checked before it is used: a FIFO does not block the
// reader, a link to a device or a huge file costs no memory, an index that does not fit the
// recording is ignored and rebuilt; a name that is not a regular file is not replaced.
TEST(RawlogIndex, WhatLiesAtItsPathIsCheckedBeforeUse) {
  IndexedFixture fx("index_path_kinds.rawlog");
  fx.policy.cache_dir = tmpPath("index_path_kinds_cache");
  const std::string idx = indexPathBeside(fx.path);
  const double t0 = fx.records.front().second;
  auto seekAndRead = [&](bool expect_loaded) {
    RawlogReader reader(fx.path, fx.policy);
    EXPECT_EQ(reader.indexLoaded(), expect_loaded);
    EXPECT_TRUE(reader.seekToTime(t0 + 1.0));
    RawlogObject rec;
    EXPECT_TRUE(reader.next(rec));
    EXPECT_EQ(rec.index, fx.firstAtOrAfter(t0 + 1.0));
    return reader.saveIndex();
  };

  // A FIFO: would block an open() for reading until a writer comes.
  ASSERT_EQ(::mkfifo(idx.c_str(), 0600), 0);
  EXPECT_NE(seekAndRead(false), idx);  // saved in the cache folder, the FIFO left alone
  EXPECT_TRUE(fs::is_fifo(idx));
  fs::remove(idx);
  fs::remove(indexPathInCache(fx.path, fx.policy.cache_dir));

  // A link to /dev/zero: endless zeros.
  fs::create_symlink("/dev/zero", idx);
  EXPECT_NE(seekAndRead(false), idx);
  EXPECT_TRUE(fs::is_symlink(idx));
  fs::remove(idx);
  fs::remove(indexPathInCache(fx.path, fx.policy.cache_dir));

  // A sparse file far larger than the rawlog: refused by its size, before any read.
  {
    std::ofstream f(idx, std::ios::binary);
    f << "FIIDX001";
  }
  fs::resize_file(idx, std::uintmax_t{3} << 30);
  EXPECT_EQ(seekAndRead(false), idx);  // replaced by a real index
  EXPECT_LT(fs::file_size(idx), fs::file_size(fx.path));
  seekAndRead(true);  // loaded, used

  // A valid index whose records no longer fit (edited): ignored, rebuilt.
  RawlogIndex index;
  ASSERT_TRUE(loadRawlogIndex(idx, rawlogIdentity(fx.path), index));
  ASSERT_GT(index.records.size(), 2u);
  std::swap(index.records[0].offset, index.records[1].offset);
  saveRawlogIndex(idx, index);
  RawlogIndex reloaded;
  EXPECT_FALSE(loadRawlogIndex(idx, rawlogIdentity(fx.path), reloaded));
  index.records[1].offset = index.records[0].offset;
  index.records[0].offset = 0;
  index.points.back().in = fs::file_size(fx.path) + 1;  // beyond the file
  saveRawlogIndex(idx, index);
  EXPECT_FALSE(loadRawlogIndex(idx, rawlogIdentity(fx.path), reloaded));
  EXPECT_EQ(seekAndRead(false), idx);
  EXPECT_TRUE(loadRawlogIndex(idx, rawlogIdentity(fx.path), reloaded));
}

// The extrinsics of a rawlog are each cloud's sensorPose relative to the IMU's, whatever the order
// of the records: a cloud before the first IMU sample (goodRecords starts with one) waits for the
// IMU's sensorPose instead of taking the cloud's own as if the IMU sat at the origin. Every later
// cloud must give the same, and every IMU sample the same sensorPose.
TEST(InputValidator, ExtrinsicsAreOneRuleWhateverTheRecordOrder) {
  const mrpt::poses::CPose3D imu_pose(0.4, -0.2, 1.1, 0.3, -0.05, 0.02);  // the IMU on a mount
  const mrpt::poses::CPose3D lidar_in_imu = poseFromExtrinsics(someExtrinsics());
  auto mounted = [&](std::vector<RawlogRecord> r) {
    for (auto& x : r)
      x.obs->setSensorPose(x.obs->GetRuntimeClass() == CLASS_ID(mrpt::obs::CObservationIMU)
                               ? imu_pose
                               : imu_pose + lidar_in_imu);
    return r;
  };
  auto expectExtrinsics = [](const CheckedRecording& in) {
    ASSERT_TRUE(in.sensor_pose_extrinsics);
    EXPECT_LT((in.sensor_pose_extrinsics->R_bl - someExtrinsics().R_bl).norm(), 1e-9);
    EXPECT_LT((in.sensor_pose_extrinsics->p_bl - someExtrinsics().p_bl).norm(), 1e-9);
  };
  const std::vector<RawlogRecord> cloud_first = mounted(goodRecords());
  ASSERT_TRUE(std::dynamic_pointer_cast<mrpt::obs::CObservationPointCloud>(cloud_first[0].obs));
  expectExtrinsics(validate(cloud_first, sensorPoseConfig(), "cloud_first.rawlog"));
  std::vector<RawlogRecord> imu_first = cloud_first;
  std::swap(imu_first[0], imu_first[1]);
  expectExtrinsics(validate(imu_first, sensorPoseConfig(), "imu_first.rawlog"));

  // A later cloud placing the LiDAR elsewhere is a bad record, named.
  std::vector<RawlogRecord> moved = cloud_first;
  std::size_t later = 0;
  for (std::size_t i = 1; i < moved.size() && later == 0; ++i)
    if (std::dynamic_pointer_cast<mrpt::obs::CObservationPointCloud>(moved[i].obs)) later = i;
  ASSERT_GT(later, 0u);
  moved[later].obs->setSensorPose(imu_pose + mrpt::poses::CPose3D(0.1, -0.05, 0.13, 0.0, 0.0, 0.0));
  expectThrowsWith([&] { validate(moved, sensorPoseConfig(), "moved.rawlog"); },
                   "record " + std::to_string(later) +
                       ": its sensorPose gives the LiDAR another pose in the IMU frame");

  // An IMU sample that moved on the platform, likewise.
  std::vector<RawlogRecord> imu_moved = cloud_first;
  imu_moved[5].obs->setSensorPose(mrpt::poses::CPose3D(0.4, -0.2, 1.2, 0.3, -0.05, 0.02));
  expectThrowsWith([&] { validate(imu_moved, sensorPoseConfig(), "imu_moved.rawlog"); },
                   "record 5: its sensorPose");

  // Configured extrinsics: the sensor poses are not read.
  const AppConfig ini = loadAppConfigFromText(
      "[extrinsics]\nfrom_sensor_pose = false\np_bl = 0.1 -0.05 0.12\n", "test.ini");
  EXPECT_NO_THROW(validate(moved, ini, "moved_ini.rawlog"));
}

// A pose whose rotation is not one (a corrupt or hand-made record) is refused on every cloud,
// not only the first.
TEST(InputValidator, ACloudWhoseExtrinsicsAreNotARigidPoseIsABadRecord) {
  RecordChecker checker(sensorPoseConfig());
  std::vector<CheckedItem> out;
  auto cloud = [](std::size_t record, double t, const Mat3& R) {
    IngestItem it;
    it.kind = IngestItem::Kind::Frame;
    it.record = record;
    it.t = t;
    it.frame = std::make_shared<LidarFrame>(randomFrame(t, 50, static_cast<unsigned>(record)));
    Extrinsics pose;
    pose.R_bl = R;
    it.sensor_pose = pose;
    return it;
  };
  IngestItem imu;
  imu.kind = IngestItem::Kind::Imu;
  imu.record = 0;
  imu.t = 1700000000.0;
  imu.imu.t = imu.t;
  imu.imu.accel = Vec3(0, 0, kGravity);
  imu.sensor_pose = Extrinsics{};
  checker.push(imu, out);
  checker.push(cloud(1, 1700000000.0, Mat3::Identity()), out);
  checker.push(cloud(2, 1700000000.1, 2.0 * Mat3::Identity()), out);
  checker.finish(out);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_TRUE(out[1].ok()) << out[1].problem;
  EXPECT_NE(out[2].problem.find("not a rigid pose"), std::string::npos) << out[2].problem;
}

// One IMU sample stamped 10 days ahead of its stream (which goes on on its clock) is dropped as an
// ignored record naming it, never handed on; the samples after it and a cloud between them come
// out in input order. A sample that comes late (earlier than the one before the held one) stays
// a bad record.
TEST(InputValidator, AnImuStampThatJumpsAheadIsDroppedAndTheStreamGoesOn) {
  const AppConfig config = loadAppConfigFromText("", "test.ini");
  RecordChecker checker(config);
  std::vector<CheckedItem> out;
  auto imu = [](std::size_t record, double t) {
    IngestItem it;
    it.kind = IngestItem::Kind::Imu;
    it.record = record;
    it.t = t;
    it.imu.t = t;
    it.imu.accel = Vec3(0, 0, kGravity);
    return it;
  };
  const double t0 = 1700000000.0;
  checker.push(imu(0, t0), out);
  checker.push(imu(1, t0 + 0.005), out);
  checker.push(imu(2, t0 + 0.010 + 864000.0), out);  // ten days ahead
  IngestItem cloud;
  cloud.kind = IngestItem::Kind::Frame;
  cloud.record = 3;
  cloud.t = t0 + 0.011;
  cloud.frame = std::make_shared<LidarFrame>(randomFrame(cloud.t, 50, 3));
  checker.push(cloud, out);
  checker.push(imu(4, t0 + 0.015), out);
  checker.push(imu(5, t0 + 0.020), out);
  checker.push(imu(6, t0 + 0.001), out);  // late: before record 5's predecessor
  checker.finish(out);
  ASSERT_EQ(out.size(), 7u);
  EXPECT_EQ(checker.stampJumps(), 1u);
  std::vector<std::size_t> imu_records;
  for (const CheckedItem& c : out)
    if (c.ok() && c.item.kind == IngestItem::Kind::Imu) imu_records.push_back(c.item.record);
  EXPECT_EQ(imu_records, (std::vector<std::size_t>{0, 1, 4, 5}));
  EXPECT_EQ(out[2].item.kind, IngestItem::Kind::Other);
  EXPECT_TRUE(out[2].ok());
  EXPECT_EQ(out[2].item.what, "IMU record 2 stamped 864000 s ahead of its stream (dropped)");
  EXPECT_EQ(out[3].item.record, 3u);  // the cloud, in input order
  EXPECT_EQ(out[4].item.record, 4u);
  // The late sample: a bad record, after record 5 (held when it came).
  EXPECT_EQ(out[5].item.record, 5u);
  EXPECT_EQ(out[6].item.record, 6u);
  EXPECT_FALSE(out[6].ok());
  // Through a session: counted as an ignored observation, the session not failed.
  InitSession session(config, "jump.rawlog");
  for (const CheckedItem& c : out) session.push(c);
  EXPECT_FALSE(session.failed());
  bool named = false;
  for (const std::string& w : session.warnings())
    named = named || w.find("IMU record 2 stamped 864000 s ahead") != std::string::npos;
  EXPECT_TRUE(named);
}
