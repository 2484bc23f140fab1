#include <freeinit/ros1/bag_writer.h>
#include <freeinit/ros1/cloud_codec.h>
#include <rosbag/bag.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_msgs/TFMessage.h>

#include <cstdio>
#include <filesystem>
#include <stdexcept>

namespace freeinit::ros1 {

void writeBag(const std::string& path, const std::vector<ImuSample>& imu,
              const std::vector<LidarFrame>& frames, const BagWriteOptions& o) {
  validate(o.config);
  const std::string tmp = path + ".tmp";
  try {
    rosbag::Bag bag(tmp, rosbag::bagmode::Write);
    using C = BagWriteOptions::Compression;
    bag.setCompression(o.compression == C::kBz2   ? rosbag::compression::BZ2
                       : o.compression == C::kLz4 ? rosbag::compression::LZ4
                                                  : rosbag::compression::Uncompressed);
    bag.setChunkThreshold(o.chunk_threshold);
    const double accel_scale = o.config.imu_accel_in_g ? 1.0 / kGravity : 1.0;
    if (!o.tf_static.empty() && !imu.empty()) {
      tf2_msgs::TFMessage tf;
      for (const ros2::TransformStamped& t : o.tf_static) {
        geometry_msgs::TransformStamped g;
        g.header.stamp =
            ros::Time(static_cast<std::uint32_t>(t.header.stamp.sec), t.header.stamp.nanosec);
        g.header.frame_id = t.header.frame_id;
        g.child_frame_id = t.child_frame_id;
        g.transform.translation.x = t.translation.x;
        g.transform.translation.y = t.translation.y;
        g.transform.translation.z = t.translation.z;
        g.transform.rotation.x = t.rotation.x;
        g.transform.rotation.y = t.rotation.y;
        g.transform.rotation.z = t.rotation.z;
        g.transform.rotation.w = t.rotation.w;
        tf.transforms.push_back(g);
      }
      bag.write(o.config.tf_static_topic, ros::Time(imu.front().t), tf);
    }
    // In bag-time order, as a recorder writes what it receives: the chunks hold both topics.
    auto writeImu = [&](std::size_t k) {
      const ImuSample& s = imu[k];
      sensor_msgs::Imu m;
      m.header.stamp = ros::Time(s.t);
      m.header.seq = static_cast<std::uint32_t>(k);
      m.header.frame_id = o.imu_frame_id;
      m.orientation_covariance[0] = -1;  // no orientation estimate
      m.angular_velocity.x = s.gyro.x();
      m.angular_velocity.y = s.gyro.y();
      m.angular_velocity.z = s.gyro.z();
      m.linear_acceleration.x = accel_scale * s.accel.x();
      m.linear_acceleration.y = accel_scale * s.accel.y();
      m.linear_acceleration.z = accel_scale * s.accel.z();
      bag.write(o.config.imu_topic, m.header.stamp, m);
    };
    auto cloudBagTime = [&](const LidarFrame& f) {
      return ros::Time(f.stamp - o.config.lidar_time_offset + o.lidar_publish_delay);
    };
    auto writeCloud = [&](const LidarFrame& f) {
      LidarFrame shifted;
      shifted.stamp = f.stamp - o.config.lidar_time_offset;
      shifted.points = f.points;
      sensor_msgs::PointCloud2 m;
      encodeCloud(shifted, o.config.cloud, o.reflectivity, o.big_endian, m);
      m.header.frame_id = o.lidar_frame_id;
      bag.write(o.config.lidar_topic, ros::Time(shifted.stamp + o.lidar_publish_delay), m);
    };
    std::size_t i = 0, j = 0;
    while (i < imu.size() || j < frames.size()) {
      if (j == frames.size() || (i < imu.size() && ros::Time(imu[i].t) <= cloudBagTime(frames[j])))
        writeImu(i++);
      else
        writeCloud(frames[j++]);
    }
    bag.close();
  } catch (const std::exception& e) {
    std::remove(tmp.c_str());
    throw std::runtime_error(path + ": cannot write the bag: " + e.what());
  }
  std::filesystem::rename(tmp, path);
}

}  // namespace freeinit::ros1
