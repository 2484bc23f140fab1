// Writes the seed corpora of the MRPT-side harnesses (fuzz/corpus/rawlog_reader/,
// fuzz/corpus/ini_loaders/): small valid rawlogs of every form the reader takes, and the shipped
// configuration files behind their loader's selector byte.
//   freeinit-fuzz-make-seeds-mrpt <corpus folder> <source folder>
#include <freeinit/mrpt_plugins/conversions.h>
#include <freeinit/mrpt_plugins/rawlog_writer.h>
#include <freeinit/mrpt_plugins/register.h>
#include <mrpt/io/CFileOutputStream.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/serialization/CArchive.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

using namespace freeinit;
namespace fs = std::filesystem;

namespace {

constexpr double kT0 = 1700000000.0;

ImuSample imu(int k) {
  ImuSample s;
  s.t = kT0 + 0.005 * k;
  s.gyro = Vec3(0.01 * k, -0.02, 0.3);
  s.accel = Vec3(0.1, -0.2, 9.8);
  return s;
}

LidarFrame frame(double stamp, int n) {
  LidarFrame f;
  f.stamp = stamp;
  for (int i = 0; i < n; ++i) {
    DopplerPoint p;
    p.p_l = Eigen::Vector3f(5.0f + i, 0.5f * i - 2, 0.1f * i);
    p.doppler = -0.125f * static_cast<float>(i % 5);
    p.time_offset = 0.002f * static_cast<float>(i);
    p.intensity = 10.0f + i;
    p.line = static_cast<std::uint16_t>(i % 4);
    f.points.push_back(p);
  }
  return f;
}

/// IMU at 200 Hz with two 8-point clouds, in time order.
std::vector<mrpt::obs::CObservation::Ptr> observations() {
  std::vector<mrpt::obs::CObservation::Ptr> out;
  const Extrinsics e;
  for (int k = 0; k < 20; ++k) {
    out.push_back(mrpt_plugins::imuToObservation(imu(k), "IMU"));
    if (k == 4 || k == 14)
      out.push_back(mrpt_plugins::frameToObservation(frame(imu(k).t + 0.001, 8), e, "LIDAR"));
  }
  return out;
}

void gz(const fs::path& p, const std::vector<mrpt::obs::CObservation::Ptr>& obs) {
  mrpt_plugins::RawlogWriter w(p.string());
  for (const auto& o : obs) w.write(*o);
  w.commit();
}

void plain(const fs::path& p, const std::vector<mrpt::serialization::CSerializable::Ptr>& objs) {
  mrpt::io::CFileOutputStream f(p.string());
  auto a = mrpt::serialization::archiveFrom(f);
  for (const auto& o : objs) a << *o;
}

void copyWithSelector(const fs::path& from, const fs::path& to, char selector) {
  std::ifstream in(from, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  std::ofstream(to, std::ios::binary) << selector << text.str();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::cerr << "usage: freeinit-fuzz-make-seeds-mrpt <corpus folder> <source folder>\n";
    return 2;
  }
  mrpt_plugins::registerClasses();
  const fs::path root(argv[1]), src(argv[2]);
  const fs::path rawlogs = root / "rawlog_reader", inis = root / "ini_loaders";
  fs::create_directories(rawlogs);
  fs::create_directories(inis);

  // Rawlogs: gzip and plain observation streams, the sensory-frame form, other classes.
  const auto obs = observations();
  gz(rawlogs / "imu_clouds.rawlog", obs);
  plain(rawlogs / "imu_clouds_plain.rawlog", {obs.begin(), obs.end()});
  gz(rawlogs / "imu_only.rawlog", {obs[0], obs[1], obs[2]});
  {
    std::vector<mrpt::serialization::CSerializable::Ptr> v;
    for (std::size_t i = 0; i < obs.size(); i += 4) {
      auto sf = mrpt::obs::CSensoryFrame::Create();
      for (std::size_t j = i; j < std::min(obs.size(), i + 4); ++j) sf->insert(obs[j]);
      v.push_back(mrpt::obs::CActionCollection::Create());
      v.push_back(sf);
    }
    plain(rawlogs / "sensory_frames.rawlog", v);
  }
  {
    auto odo = mrpt::obs::CObservationOdometry::Create();
    odo->sensorLabel = "ODOMETRY";
    odo->timestamp = mrpt_plugins::fromUnix(kT0 + 0.002);
    auto scan = mrpt::obs::CObservation2DRangeScan::Create();
    scan->sensorLabel = "SCAN";
    scan->timestamp = mrpt_plugins::fromUnix(kT0 + 0.003);
    scan->resizeScan(5);
    for (int i = 0; i < 5; ++i)
      scan->setScanRange(i, 1.0f + i), scan->setScanRangeValidity(i, true);
    auto stock = mrpt::obs::CObservationPointCloud::Create();
    stock->sensorLabel = "LIDAR";
    stock->timestamp = mrpt_plugins::fromUnix(kT0 + 0.004);
    auto pts = mrpt::maps::CSimplePointsMap::Create();
    pts->insertPoint(1, 2, 3);
    stock->pointcloud = pts;
    gz(rawlogs / "other_classes.rawlog", {obs[0], odo, scan, stock, obs[1]});
  }

  // Configuration files, behind the selector byte of fuzz_ini_loaders.cpp.
  copyWithSelector(src / "ini" / "freeinit.ini", inis / "0_freeinit.ini", 0);
  copyWithSelector(src / "ini" / "freeinit_radar.ini", inis / "0_freeinit_radar.ini", 0);
  copyWithSelector(src / "ini" / "import_bag.ini", inis / "1_import_bag.ini", 1);
  copyWithSelector(src / "ini" / "import_bag_ti_mmwave.ini", inis / "1_import_bag_ti_mmwave.ini",
                   1);
  std::ofstream(inis / "2_scenario.ini", std::ios::binary)
      << '\2' << "; a short scenario\n[scenario]\npreset = stat_01\nseed = 7\nimu_rate = 100\n"
      << "duration = 0.5\nb_g = 0.01 -0.02 0.005\n";
  copyWithSelector(src / "ini" / "icp_slam.ini", inis / "3_icp_slam.ini", 3);
  std::ofstream(inis / "4_parser.ini", std::ios::binary)
      << '\4' << "# comment\n[a]\nkey = \"quoted value\" ; comment\nlist = 1 2 3\n\n[B]\nx=1\n";
  std::cout << "seeds written to " << rawlogs.string() << " and " << inis.string() << "\n";
  return 0;
}
