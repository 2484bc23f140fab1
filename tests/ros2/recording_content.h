// Test helpers: every message of a recording decoded and written as one line of text, so that
// recordings can be compared message by message (and a difference shows as text).
#pragma once

#include <freeinit/ros2/message_decoding.h>
#include <freeinit/ros2/recording.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <string>
#include <vector>

namespace freeinit::ros2::test {

inline std::string recordingsDir() { return FREEINIT_ROS2_RECORDINGS; }
inline std::string fixture(const std::string& name) { return recordingsDir() + "/" + name; }

/// The bytes of a file (through its buffer: an istreambuf_iterator range makes GCC 12 warn of a
/// null dereference inside the standard library).
inline std::string fileBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

/// One point of the Aeva layout of the fixtures, read by field name in the cloud's byte order.
struct AevaPoint {
  float x = 0, y = 0, z = 0, intensity = 0, reflectivity = 0, velocity = 0;
  std::int32_t time_offset_ns = 0;
  std::uint8_t line_index = 0;
};

template <class T>
T loadValue(const std::uint8_t* p, bool big_endian) {
  std::uint8_t b[sizeof(T)];
  std::memcpy(b, p, sizeof(T));
  if (big_endian)
    for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
  T v;
  std::memcpy(&v, b, sizeof(T));
  return v;
}

inline std::vector<AevaPoint> aevaPoints(const PointCloud2& c) {
  auto offset = [&](const char* name) -> std::uint32_t {
    for (const PointField& f : c.fields)
      if (f.name == name) return f.offset;
    throw std::runtime_error(std::string("no field ") + name);
  };
  std::vector<AevaPoint> points;
  for (std::uint32_t i = 0; i < c.width * c.height; ++i) {
    const std::uint8_t* p = c.data.data() + std::size_t{i} * c.point_step;
    const bool be = c.is_bigendian;
    AevaPoint a;
    a.x = loadValue<float>(p + offset("x"), be);
    a.y = loadValue<float>(p + offset("y"), be);
    a.z = loadValue<float>(p + offset("z"), be);
    a.intensity = loadValue<float>(p + offset("intensity"), be);
    a.reflectivity = loadValue<float>(p + offset("reflectivity"), be);
    a.velocity = loadValue<float>(p + offset("velocity"), be);
    a.time_offset_ns = loadValue<std::int32_t>(p + offset("time_offset_ns"), be);
    a.line_index = p[offset("line_index")];
    points.push_back(a);
  }
  return points;
}

inline void put(std::ostringstream& os, double v) { os << ' ' << std::setprecision(17) << v; }

inline std::string header(const Header& h) {
  return std::to_string(h.stamp.sec) + " " + std::to_string(h.stamp.nanosec) + " " + h.frame_id;
}

/// One line per message: topic, log time and every decoded value (clouds: every point's values,
/// whatever the byte order of the data).
inline std::string describeMessage(const Recording& r, const Message& m) {
  const TopicInfo& t = r.topics()[m.topic];
  std::ostringstream os;
  os << t.name << ' ' << m.log_time;
  if (t.type == kImuType) {
    const Imu i = decodeImu(m.data);
    os << ' ' << header(i.header);
    for (double v : {i.orientation.x, i.orientation.y, i.orientation.z, i.orientation.w})
      put(os, v);
    for (double v : i.orientation_covariance) put(os, v);
    for (double v : {i.angular_velocity.x, i.angular_velocity.y, i.angular_velocity.z}) put(os, v);
    for (double v : i.angular_velocity_covariance) put(os, v);
    for (double v : {i.linear_acceleration.x, i.linear_acceleration.y, i.linear_acceleration.z})
      put(os, v);
    for (double v : i.linear_acceleration_covariance) put(os, v);
  } else if (t.type == kPointCloud2Type) {
    const PointCloud2 c = decodePointCloud2(m.data);
    os << ' ' << header(c.header) << ' ' << c.height << ' ' << c.width << ' ' << c.point_step << ' '
       << c.row_step << ' ' << c.is_dense;
    for (const PointField& f : c.fields)
      os << ' ' << f.name << ':' << f.offset << ':' << int{f.datatype} << ':' << f.count;
    for (const AevaPoint& p : aevaPoints(c)) {
      for (double v : {p.x, p.y, p.z, p.intensity, p.reflectivity, p.velocity}) put(os, v);
      os << ' ' << p.time_offset_ns << ' ' << int{p.line_index};
    }
  } else if (t.type == kTFMessageType) {
    for (const TransformStamped& s : decodeTFMessage(m.data).transforms) {
      os << ' ' << header(s.header) << ' ' << s.child_frame_id;
      for (double v : {s.translation.x, s.translation.y, s.translation.z, s.rotation.x,
                       s.rotation.y, s.rotation.z, s.rotation.w})
        put(os, v);
    }
  }
  return os.str();
}

/// Every message read with `options`, described.
inline std::vector<std::string> describeAll(Recording& r, const ReadOptions& options = {}) {
  std::vector<std::string> lines;
  r.start(options);
  Message m;
  while (r.next(m)) lines.push_back(describeMessage(r, m));
  return lines;
}

/// Every message's log time and topic name.
inline std::vector<std::pair<std::int64_t, std::string>> stamps(Recording& r,
                                                                const ReadOptions& o = {}) {
  std::vector<std::pair<std::int64_t, std::string>> v;
  r.start(o);
  Message m;
  while (r.next(m)) v.emplace_back(m.log_time, r.topics()[m.topic].name);
  return v;
}

}  // namespace freeinit::ros2::test
