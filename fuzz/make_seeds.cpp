// Writes the seed corpora of the fuzz harnesses (fuzz/corpus/<harness>/): small valid inputs of
// every kind each harness reads, so that fuzzing starts from the formats' structure.
//   freeinit-fuzz-make-seeds <corpus folder>
// The committed corpora were made with it; rerun it after a format change.
#include <freeinit/net/wire_format.h>
#include <freeinit/ros1/bag_writer.h>
#include <freeinit/ros1/cloud_codec.h>
#include <ros/serialization.h>
#include <rosbag/bag.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_msgs/Header.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>

using namespace freeinit;
namespace fs = std::filesystem;

namespace {

constexpr double kT0 = 1700000000.0;

std::vector<ImuSample> imuSamples(int n) {
  std::vector<ImuSample> v;
  for (int k = 0; k < n; ++k) {
    ImuSample s;
    s.t = kT0 + 0.005 * k;
    s.gyro = Vec3(0.01 * k, -0.02, 0.3);
    s.accel = Vec3(0.1, -0.2, 9.8);
    v.push_back(s);
  }
  return v;
}

LidarFrame frame(double stamp, int n, bool with_time) {
  LidarFrame f;
  f.stamp = stamp;
  for (int i = 0; i < n; ++i) {
    DopplerPoint p;
    p.p_l = Eigen::Vector3f(5.0f + i, 0.5f * i - 2, 0.1f * i);
    p.doppler = -0.125f * static_cast<float>(i % 5);
    p.time_offset = with_time ? 0.01f * static_cast<float>(i) : 0.0f;
    p.intensity = 10.0f + i;
    p.line = static_cast<std::uint16_t>(i % 4);
    f.points.push_back(p);
  }
  return f;
}

void save(const fs::path& p, const std::vector<std::uint8_t>& bytes) {
  std::ofstream(p, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()),
             static_cast<std::streamsize>(bytes.size()));
}

template <class T>
std::vector<std::uint8_t> serialized(const T& msg) {
  std::vector<std::uint8_t> b(ros::serialization::serializationLength(msg));
  ros::serialization::OStream out(b.data(), static_cast<std::uint32_t>(b.size()));
  ros::serialization::serialize(out, msg);
  return b;
}

ros1::CloudLayout radarLayout() {
  ros1::CloudLayout l;
  l.time.field.name.clear();
  l.time.frame_duration = 0.0185;
  l.line.name.clear();
  return l;
}

// A radar-like bag: /imu, /radar clouds with zero stamps and a seq, and (optionally) /trigger
// std_msgs/Header messages carrying each scan's stamp under the same seq.
void radarBag(const fs::path& path, bool triggers) {
  rosbag::Bag bag(path.string(), rosbag::bagmode::Write);
  for (const ImuSample& s : imuSamples(30)) {
    sensor_msgs::Imu m;
    m.header.stamp = ros::Time(s.t);
    m.angular_velocity.x = s.gyro.x();
    m.angular_velocity.y = s.gyro.y();
    m.angular_velocity.z = s.gyro.z();
    m.linear_acceleration.x = s.accel.x();
    m.linear_acceleration.y = s.accel.y();
    m.linear_acceleration.z = s.accel.z();
    bag.write("/imu", m.header.stamp, m);
  }
  for (std::uint32_t k = 0; k < 2; ++k) {
    const double t = kT0 + 0.02 + 0.05 * k;
    std_msgs::Header h;
    h.seq = 100 + k;
    h.stamp = ros::Time(t);
    if (triggers) bag.write("/trigger", ros::Time(t + 0.001), h);
    sensor_msgs::PointCloud2 c;
    ros1::encodeCloud(frame(t, 6, false), radarLayout(), false, false, c);
    c.header.stamp = ros::Time();
    c.header.seq = 100 + k;
    bag.write("/radar", ros::Time(t + 0.03), c);
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: freeinit-fuzz-make-seeds <corpus folder>\n";
    return 2;
  }
  const fs::path root(argv[1]);
  for (const char* h : {"bag_reader", "cloud_decoder", "wire_format", "stream_receiver"})
    fs::create_directories(root / h);

  // Bags: the release layout (uncompressed, lz4, bz2) and the radar-like ones.
  const std::vector<LidarFrame> frames = {frame(kT0 + 0.02, 8, true), frame(kT0 + 0.07, 8, true)};
  using C = ros1::BagWriteOptions::Compression;
  for (const auto& [name, c] :
       {std::pair{"release.bag", C::kNone}, std::pair{"release_lz4.bag", C::kLz4},
        std::pair{"release_bz2.bag", C::kBz2}}) {
    ros1::BagWriteOptions o;
    o.compression = c;
    o.lidar_publish_delay = 0.03;
    ros1::writeBag((root / "bag_reader" / name).string(), imuSamples(30), frames, o);
  }
  radarBag(root / "bag_reader" / "radar_trigger.bag", true);
  radarBag(root / "bag_reader" / "radar_bag_time.bag", false);

  // Clouds: byte 0 = layout (see fuzz_cloud_decoder.cpp), then the serialized message.
  for (int layout = 0; layout < 4; ++layout) {
    ros1::CloudLayout l;
    if (layout == 1) {
      l.time.field = {"t", ros1::FieldType::kFloat32};
      l.time.scale = 1;
      l.line.name.clear();
    } else if (layout == 2) {
      for (ros1::FieldSpec* f : {&l.x, &l.y, &l.z, &l.doppler, &l.intensity})
        f->type = ros1::FieldType::kFloat64;
      l.time.field = {"t", ros1::FieldType::kFloat64};
      l.time.scale = 1;
      l.line.name.clear();
    } else if (layout == 3) {
      l = radarLayout();
    }
    sensor_msgs::PointCloud2 msg;
    ros1::encodeCloud(frame(kT0, 5, layout != 3), l, layout == 0, layout == 1, msg);
    std::vector<std::uint8_t> b = serialized(msg);
    b.insert(b.begin(), static_cast<std::uint8_t>(layout));
    save(root / "cloud_decoder" / ("layout" + std::to_string(layout) + ".bin"), b);
    if (layout == 0) {  // organized, with a NaN point, invalid points an error (bit 7)
      msg.height = 1;
      const float nan = std::nanf("");
      std::memcpy(&msg.data[msg.point_step], &nan, 4);
      msg.is_dense = false;
      b = serialized(msg);
      b.insert(b.begin(), static_cast<std::uint8_t>(0x80));
      save(root / "cloud_decoder" / "layout0_nan_strict.bin", b);
    }
  }

  // Datagrams of the live wire format.
  std::uint64_t seq = 0;
  std::vector<net::ImuMessage> imu(2);
  imu[0].stamp_ns = 1'700'000'000'000'000'000;
  imu[0].gyro = Vec3(0.1, 0.2, 0.3);
  imu[0].accel = Vec3(0, 0, 9.81);
  imu[1] = imu[0];
  imu[1].stamp_ns += 5'000'000;
  save(root / "wire_format" / "imu.bin", net::encodeImu(imu, 42, seq));
  net::FrameMessage fm;
  fm.frame_id = 7;
  fm.stamp_ns = imu[0].stamp_ns + 1'000'000;
  fm.points = frame(kT0, 12, true).points;
  const std::size_t small = net::kMinDatagram + 4 * net::kPointBytes;  // 5 points per chunk
  const auto chunks = net::encodeFrame(fm, 42, seq, small);
  save(root / "wire_format" / "chunk0.bin", chunks[0]);
  save(root / "wire_format" / "chunk_last.bin", chunks.back());
  save(root / "wire_format" / "end.bin", net::encodeEndOfStream(42, seq));

  // A stream: IMU, a frame in three chunks (the middle one late), more IMU, the end; each
  // datagram as a record of fuzz_stream_receiver.cpp (5 ms apart).
  std::vector<std::vector<std::uint8_t>> stream;
  seq = 0;
  stream.push_back(net::encodeImu({imu[0]}, 9, seq));
  const auto c3 = net::encodeFrame(fm, 9, seq, small);
  stream.push_back(c3[0]);
  stream.push_back(c3[2]);
  stream.push_back(c3[1]);
  net::ImuMessage later = imu[1];
  later.stamp_ns += 20'000'000;
  stream.push_back(net::encodeImu({imu[1], later}, 9, seq));
  stream.push_back(net::encodeEndOfStream(9, seq));
  std::vector<std::uint8_t> records;
  for (const auto& d : stream) {
    records.push_back(5);
    records.push_back(static_cast<std::uint8_t>(d.size() & 0xFF));
    records.push_back(static_cast<std::uint8_t>(d.size() >> 8));
    records.insert(records.end(), d.begin(), d.end());
  }
  save(root / "stream_receiver" / "stream.bin", records);
  std::cout << "seeds written to " << root.string() << "\n";
  return 0;
}
