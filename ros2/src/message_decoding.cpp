#include <freeinit/ros2/message_decoding.h>

#include <array>
#include <utility>

namespace freeinit::ros2 {
namespace {

// The smallest serialized sizes of sequence elements: a count of n elements is refused unless
// n times this fits in what is left. PointField: an empty name (4) + offset (4) + datatype (1) +
// count (4); TransformStamped: header (4 + 4 + 4) + child frame (4) + 7 float64.
constexpr std::size_t kMinPointFieldBytes = 13;
constexpr std::size_t kMinTransformBytes = 72;

Header readHeader(CdrReader& r) {
  Header h;
  h.stamp.sec = r.int32("header.stamp.sec");
  h.stamp.nanosec = r.uint32("header.stamp.nanosec");
  h.frame_id = r.string("header.frame_id");
  return h;
}

Vector3 readVector3(CdrReader& r, const char* what) {
  Vector3 v;
  v.x = r.float64(what);
  v.y = r.float64(what);
  v.z = r.float64(what);
  return v;
}

Quaternion readQuaternion(CdrReader& r, const char* what) {
  Quaternion q;
  q.x = r.float64(what);
  q.y = r.float64(what);
  q.z = r.float64(what);
  q.w = r.float64(what);
  return q;
}

void readCovariance(CdrReader& r, std::array<double, 9>& c, const char* what) {
  for (double& v : c) v = r.float64(what);
}

}  // namespace

Imu decodeImu(const std::uint8_t* data, std::size_t size) {
  CdrReader r(data, size);
  Imu m;
  m.header = readHeader(r);
  m.orientation = readQuaternion(r, "Imu.orientation");
  readCovariance(r, m.orientation_covariance, "Imu.orientation_covariance");
  m.angular_velocity = readVector3(r, "Imu.angular_velocity");
  readCovariance(r, m.angular_velocity_covariance, "Imu.angular_velocity_covariance");
  m.linear_acceleration = readVector3(r, "Imu.linear_acceleration");
  readCovariance(r, m.linear_acceleration_covariance, "Imu.linear_acceleration_covariance");
  return m;
}

PointCloud2 decodePointCloud2(const std::uint8_t* data, std::size_t size) {
  CdrReader r(data, size);
  PointCloud2 m;
  m.header = readHeader(r);
  m.height = r.uint32("PointCloud2.height");
  m.width = r.uint32("PointCloud2.width");
  const std::uint32_t n = r.sequenceLength(kMinPointFieldBytes, "PointCloud2.fields");
  for (std::uint32_t i = 0; i < n; ++i) {
    PointField f;
    f.name = r.string("PointCloud2.fields[].name");
    f.offset = r.uint32("PointCloud2.fields[].offset");
    f.datatype = r.uint8("PointCloud2.fields[].datatype");
    f.count = r.uint32("PointCloud2.fields[].count");
    m.fields.push_back(std::move(f));
  }
  m.is_bigendian = r.boolean("PointCloud2.is_bigendian");
  m.point_step = r.uint32("PointCloud2.point_step");
  m.row_step = r.uint32("PointCloud2.row_step");
  r.bytes(m.data, "PointCloud2.data");
  m.is_dense = r.boolean("PointCloud2.is_dense");
  return m;
}

TFMessage decodeTFMessage(const std::uint8_t* data, std::size_t size) {
  CdrReader r(data, size);
  TFMessage m;
  const std::uint32_t n = r.sequenceLength(kMinTransformBytes, "TFMessage.transforms");
  for (std::uint32_t i = 0; i < n; ++i) {
    TransformStamped t;
    t.header = readHeader(r);
    t.child_frame_id = r.string("TFMessage.transforms[].child_frame_id");
    t.translation = readVector3(r, "TFMessage.transforms[].transform.translation");
    t.rotation = readQuaternion(r, "TFMessage.transforms[].transform.rotation");
    m.transforms.push_back(std::move(t));
  }
  return m;
}

}  // namespace freeinit::ros2
