// What a corrupt rawlog record may cost: the per-record allocation budget of the rawlog reader
// (read_budget.h, with the program's allocation guard linked in as in the apps), the point count
// of a Doppler cloud, the IMU presence flags, and the INI MRPT parses for freeinit-icp-slam.
// Each error is one line naming the file and the record (or key).
#include <freeinit/app_support/app_config.h>
#include <freeinit/mrpt_plugins/conversions.h>
#include <freeinit/mrpt_plugins/rawlog_reader.h>
#include <freeinit/mrpt_plugins/rawlog_writer.h>
#include <freeinit/mrpt_plugins/read_budget.h>
#include <gtest/gtest.h>
#include <mrpt/core/exceptions.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/serialization/CArchive.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <new>
#include <sstream>
#include <vector>

#include "icp_slam_app.h"

using namespace freeinit;
using namespace freeinit::mrpt_plugins;
using namespace freeinit::app_support;
using namespace freeinit::apps;
namespace fs = std::filesystem;

namespace {

const std::string kSrc = FREEINIT_SOURCE_DIR;

std::string tmpPath(const std::string& name) {
  const auto dir = fs::temp_directory_path() / "freeinit_bad_records_tests";
  fs::create_directories(dir);
  return (dir / name).string();
}

LidarFrame frame(double stamp, std::size_t n) {
  LidarFrame f;
  f.stamp = stamp;
  for (std::size_t i = 0; i < n; ++i) {
    DopplerPoint p;
    p.p_l = Eigen::Vector3f(10.0f + static_cast<float>(i % 100), 1.0f, 0.5f);
    p.doppler = 0.25f;
    p.time_offset = 0.1f * static_cast<float>(i) / static_cast<float>(n);
    f.points.push_back(p);
  }
  return f;
}

ImuSample imu(double t) {
  ImuSample s;
  s.t = t;
  s.accel = Vec3(0, 0, kGravity);
  return s;
}

/// The objects serialized back to back (a plain rawlog).
std::string serialize(const std::vector<mrpt::serialization::CSerializable::Ptr>& objs) {
  mrpt::io::CMemoryStream buf;
  auto a = mrpt::serialization::archiveFrom(buf);
  for (const auto& o : objs) a << *o;
  return std::string(static_cast<const char*>(buf.getRawBufferData()), buf.getTotalBytesCount());
}

void save(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

/// Replaces the first little-endian uint32 `from` found after `after` by `to`.
void patchCount(std::string& bytes, const std::string& after, std::uint32_t from,
                std::uint32_t to) {
  const auto start = bytes.find(after);
  ASSERT_NE(start, std::string::npos) << after;
  char f[4], t[4];
  std::memcpy(f, &from, 4);
  std::memcpy(t, &to, 4);
  const auto pos = bytes.find(std::string(f, 4), start);
  ASSERT_NE(pos, std::string::npos) << "count " << from << " after " << after;
  bytes.replace(pos, 4, std::string(t, 4));
}

/// The error of reading the whole file with a record budget of `max_bytes`, "" when it reads.
std::string readError(const std::string& path, std::size_t max_bytes = std::size_t{256} << 20) {
  try {
    RawlogReader reader(path);
    reader.setMaxRecordBytes(max_bytes);
    RawlogObject r;
    while (reader.next(r)) {
    }
    return "";
  } catch (const InputError& e) {
    return e.what();
  }
}

void expectOneLineNaming(const std::string& m, const std::string& path, const std::string& record,
                         const std::string& what) {
  EXPECT_EQ(m.find('\n'), std::string::npos) << m;
  EXPECT_EQ(m.rfind(path, 0), 0u) << m;
  EXPECT_NE(m.find(record), std::string::npos) << m;
  EXPECT_NE(m.find(what), std::string::npos) << m;
}

}  // namespace

TEST(ReadBudget, TheGuardRefusesALargeRequestOverTheOpenBudget) {
  ASSERT_TRUE(ReadBudget::enforced()) << "the allocation guard is not linked into this test";
  const std::size_t large = ReadBudget::kLargeRequest;
  {
    ReadBudget budget(3 * large);
    auto first = std::make_unique<char[]>(2 * large);
    EXPECT_EQ(budget.refused(), 0u);
    EXPECT_GE(budget.charged(), 2 * large);
    // 2 + 2 > 3: this one does not fit.
    EXPECT_THROW(std::make_unique<char[]>(2 * large), std::bad_alloc);
    EXPECT_EQ(budget.refused(), 2 * large);
    // Small requests are counted, never refused.
    auto small = std::make_unique<char[]>(large / 2);
    EXPECT_GE(budget.charged(), 2 * large + large / 2);
  }
  // Closed: no limit.
  EXPECT_NO_THROW(std::make_unique<char[]>(std::size_t{8} << 20));
}

TEST(ReadBudget, MrptCanDescribeAnErrorOnceTheBudgetIsSpent) {
  // MRPT builds an exception's message, with a backtrace, inside what(), which may not throw: a
  // refusal there terminated the program (found by fuzzing the rawlog reader).
  ReadBudget budget(ReadBudget::kLargeRequest);
  auto all = std::make_unique<char[]>(ReadBudget::kLargeRequest);
  try {
    THROW_EXCEPTION("corrupt data");
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("corrupt data"), std::string::npos);
  }
  EXPECT_EQ(budget.refused(), 0u);
}

TEST(RawlogReader, ARecordOverTheConfiguredMaximumIsRefusedNamingTheKey) {
  // A valid 60,000-point cloud (about 1.6 MB in memory) after one IMU sample: read whole with the
  // default maximum, refused at record 1 with a 1 MB one.
  const std::string p = tmpPath("big_cloud.rawlog");
  {
    RawlogWriter w(p);
    w.write(*imuToObservation(imu(1700000000.0), "IMU"));
    w.write(*frameToObservation(frame(1700000000.01, 60000), Extrinsics(), "LIDAR"));
    w.commit();
  }
  EXPECT_EQ(readError(p), "");
  const std::string m = readError(p, 1000000);
  expectOneLineNaming(m, p, "record 1", "max_record_mb");
  EXPECT_NE(m.find("1.0 MB"), std::string::npos) << m;
}

TEST(RawlogReader, AValidCloudIsChargedItsSizeNotTheGrowthOfItsFields) {
  // 400,000 points: 10 MB of fields in memory. Read as its data arrive, each field vector grew
  // by doubling and every earlier block was charged too (24 MB): a valid cloud then looked like
  // a corrupt count. Where the budget vouches for the count, the fields are allocated once.
  const std::string p = tmpPath("cloud_of_its_size.rawlog");
  {
    RawlogWriter w(p);
    w.write(*imuToObservation(imu(1700000000.0), "IMU"));
    w.write(*frameToObservation(frame(1700000000.01, 400000), Extrinsics(), "LIDAR"));
    w.commit();
  }
  EXPECT_EQ(readError(p, 16000000), "");
  // Below its size it is refused, and the message adds up: what it asked for on top of what it
  // had allocated.
  const std::string m = readError(p, 6000000);
  expectOneLineNaming(m, p, "record 1", "max_record_mb");
  EXPECT_NE(m.find(" on top of the "), std::string::npos) << m;
  EXPECT_NE(m.find("more than the 6.0 MB a record may take"), std::string::npos) << m;
}

TEST(RawlogReader, ACountBeyondWhatTheFileHoldsIsRefusedBeforeAllocating) {
  // A stock points map declaring 50 million points (600 MB of coordinates) in a file of a few KB:
  // MRPT would allocate them before reading; the budget of the record (what the rest of the file
  // can hold) refuses the allocation.
  auto cloud = mrpt::obs::CObservationPointCloud::Create();
  cloud->sensorLabel = "LIDAR";
  cloud->timestamp = fromUnix(1700000000.0);
  auto pts = mrpt::maps::CSimplePointsMap::Create();
  for (int i = 0; i < 37; ++i) pts->insertPoint(1.0f + i, 2, 3);
  cloud->pointcloud = pts;
  std::string bytes = serialize({imuToObservation(imu(1700000000.0), "IMU"), cloud});
  patchCount(bytes, "CSimplePointsMap", 37, 50000000);
  const std::string p = tmpPath("huge_count.rawlog");
  save(p, bytes);
  const std::string m = readError(p);
  expectOneLineNaming(m, p, "record 1", "more than the rest of the file can hold");
}

TEST(RawlogReader, ADopplerCloudDeclaringMorePointsThanTheFileHoldsFailsWhereTheDataEnd) {
  // 10 million points declared (below the class's limit of 2^26) for 40 stored: the fields are
  // read as their bytes arrive, so the read fails at the end of the data, not at the allocator.
  std::string bytes = serialize({frameToObservation(frame(1700000000.0, 40), Extrinsics(), "LIDAR"),
                                 imuToObservation(imu(1700000000.01), "IMU")});
  patchCount(bytes, "CPointsMapDoppler", 40, 10000000);
  const std::string p = tmpPath("doppler_count.rawlog");
  save(p, bytes);
  const std::string short_data = readError(p);
  expectOneLineNaming(short_data, p, "record 0", "the file ends inside this record");
  EXPECT_NE(short_data.find("a corrupt length or count; no record before it"), std::string::npos)
      << short_data;

  // 2^32 - 1 points: over the class's limit, refused at once.
  patchCount(bytes, "CPointsMapDoppler", 10000000, 0xffffffffu);
  save(p, bytes);
  const std::string m = readError(p);
  expectOneLineNaming(m, p, "record 0", "4294967295 points declared for one cloud");
  EXPECT_NE(m.find("CPointsMapDoppler"), std::string::npos) << m;
}

TEST(Conversions, AnImuPresenceFlagOtherThanZeroOrOneIsCorruptData) {
  // MRPT deserializes the flags as raw bytes: a corrupt file can hold any byte there.
  auto obs = imuToObservation(imu(1700000000.0), "IMU");
  EXPECT_NO_THROW(imuFromObservation(*obs));
  const std::uint8_t bad = 32;
  std::memcpy(reinterpret_cast<std::uint8_t*>(obs->dataIsPresent.data()) + 7, &bad, 1);
  try {
    imuFromObservation(*obs);
    FAIL() << "a presence flag of 32 was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("presence flag is byte 32"), std::string::npos)
        << e.what();
  }
}

TEST(AppConfig, MaxRecordMbIsCheckedOnLoad) {
  EXPECT_DOUBLE_EQ(
      loadAppConfigFromText("[input]\nmax_record_mb = 64\n", "a.ini").input.max_record_mb, 64.0);
  try {
    loadAppConfigFromText("[input]\nmax_record_mb = 0\n", "a.ini");
    FAIL() << "max_record_mb = 0 was accepted";
  } catch (const std::exception& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("a.ini"), std::string::npos) << m;
    EXPECT_NE(m.find("max_record_mb"), std::string::npos) << m;
  }
}

TEST(IcpSlamInputs, AnIniMrptCannotParseIsOneLineNamingTheFile) {
  // MRPT's parser throws on an unterminated ${...} with a backtrace and no file name.
  const fs::path dir = fs::path(tmpPath("icp_dollar"));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string ini = (dir / "icp.ini").string();
  std::ofstream(ini) << "[MappingApplication]\nlogOutput_dir = ${FOO\n[ICP]\n";
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
    const std::string m = e.what();
    EXPECT_EQ(m.rfind(ini + ": cannot be read as an icp-slam INI: ", 0), 0u) << m;
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
    EXPECT_EQ(m.find("backtrace"), std::string::npos) << m;
  }
  EXPECT_FALSE(fs::exists(dir / "out"));
}
