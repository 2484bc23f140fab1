#include <freeinit/ros1/cloud_codec.h>
#include <sensor_msgs/PointCloud2.h>

namespace freeinit::ros1 {

bags::PointCloudView view(const sensor_msgs::PointCloud2& msg,
                          std::vector<ros2::PointField>& fields) {
  fields.resize(msg.fields.size());
  for (std::size_t i = 0; i < fields.size(); ++i) {
    fields[i].name = msg.fields[i].name;
    fields[i].offset = msg.fields[i].offset;
    fields[i].datatype = msg.fields[i].datatype;
    fields[i].count = msg.fields[i].count;
  }
  bags::PointCloudView v;
  v.stamp_sec = msg.header.stamp.sec;
  v.stamp_nanosec = msg.header.stamp.nsec;
  v.height = msg.height;
  v.width = msg.width;
  v.point_step = msg.point_step;
  v.row_step = msg.row_step;
  v.is_bigendian = msg.is_bigendian != 0;
  v.fields = &fields;
  v.data = msg.data.data();
  v.size = msg.data.size();
  return v;
}

LidarFrame decodeCloud(const sensor_msgs::PointCloud2& msg, const CloudLayout& layout,
                       bool drop_invalid, DecodeStats* stats) {
  std::vector<ros2::PointField> fields;
  return bags::decodeCloud(view(msg, fields), layout, drop_invalid, stats);
}

void encodeCloud(const LidarFrame& frame, const CloudLayout& layout, bool reflectivity,
                 bool big_endian, sensor_msgs::PointCloud2& msg) {
  ros2::PointCloud2 m;
  bags::encodeCloud(frame, layout, reflectivity, big_endian, m);
  msg = sensor_msgs::PointCloud2();
  msg.header.stamp =
      ros::Time(static_cast<std::uint32_t>(m.header.stamp.sec), m.header.stamp.nanosec);
  msg.header.frame_id = m.header.frame_id;
  msg.height = m.height;
  msg.width = m.width;
  msg.fields.resize(m.fields.size());
  for (std::size_t i = 0; i < m.fields.size(); ++i) {
    msg.fields[i].name = m.fields[i].name;
    msg.fields[i].offset = m.fields[i].offset;
    msg.fields[i].datatype = m.fields[i].datatype;
    msg.fields[i].count = m.fields[i].count;
  }
  msg.is_bigendian = m.is_bigendian;
  msg.point_step = m.point_step;
  msg.row_step = m.row_step;
  msg.data = std::move(m.data);
  msg.is_dense = m.is_dense;
}

}  // namespace freeinit::ros1
