// One recording written eight ways by independent writers (fixtures/generate.mjs: the MCAP
// project's writer with each chunk compression, without summary, out of log-time order, with
// big-endian CDR; SQLite for rosbag2 .db3 files and split folders, mcap folders): every one reads
// to the same messages, those hold what the generator wrote (expected.txt), their Doppler and
// specific force are those of the generator's motion, and any window reads what skipping reads.
#include <freeinit/ros2/message_decoding.h>
#include <freeinit/ros2/open_recording.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "recording_content.h"

namespace freeinit::ros2 {
namespace {

using test::fixture;

const std::vector<std::string> kRecordings = {
    "imu_cloud.mcap",           "imu_cloud_zstd.mcap", "imu_cloud_lz4.mcap", "imu_cloud_be.mcap",
    "imu_cloud_nosummary.mcap", "imu_cloud_db3",       "imu_cloud.db3",      "imu_cloud_mcap"};

std::vector<std::vector<std::string>> expectedLines() {
  std::ifstream in(fixture("expected.txt"));
  std::vector<std::vector<std::string>> lines;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream s(line);
    std::vector<std::string> words;
    std::string w;
    while (s >> w) words.push_back(w);
    lines.push_back(words);
  }
  return lines;
}

double num(const std::string& s) { return std::stod(s); }

TEST(Ros2Recordings, TheReferenceHoldsWhatTheGeneratorWrote) {
  const auto expected = expectedLines();
  const auto r = openRecording(fixture("imu_cloud.mcap"));
  Message m;
  std::size_t i = 0;
  while (r->next(m)) {
    ASSERT_LT(i, expected.size());
    const std::vector<std::string>& e = expected[i++];
    const TopicInfo& topic = r->topics()[m.topic];
    EXPECT_EQ(std::to_string(m.log_time), e[1]);
    if (e[0] == "imu") {
      ASSERT_EQ(topic.type, kImuType);
      const Imu imu = decodeImu(m.data);
      EXPECT_EQ(std::to_string(imu.header.stamp.sec), e[2]);
      EXPECT_EQ(std::to_string(imu.header.stamp.nanosec), e[3]);
      EXPECT_EQ(imu.header.frame_id, e[4]);
      const std::array<double, 19> got = {imu.orientation.x,
                                          imu.orientation.y,
                                          imu.orientation.z,
                                          imu.orientation.w,
                                          imu.orientation_covariance[0],
                                          imu.orientation_covariance[4],
                                          imu.orientation_covariance[8],
                                          imu.angular_velocity.x,
                                          imu.angular_velocity.y,
                                          imu.angular_velocity.z,
                                          imu.angular_velocity_covariance[0],
                                          imu.angular_velocity_covariance[4],
                                          imu.angular_velocity_covariance[8],
                                          imu.linear_acceleration.x,
                                          imu.linear_acceleration.y,
                                          imu.linear_acceleration.z,
                                          imu.linear_acceleration_covariance[0],
                                          imu.linear_acceleration_covariance[4],
                                          imu.linear_acceleration_covariance[8]};
      for (std::size_t k = 0; k < 19; ++k) EXPECT_EQ(got[k], num(e[5 + k])) << "imu value " << k;
    } else if (e[0] == "cloud") {
      ASSERT_EQ(topic.type, kPointCloud2Type);
      const PointCloud2 c = decodePointCloud2(m.data);
      EXPECT_EQ(std::to_string(c.header.stamp.nanosec), e[3]);
      EXPECT_EQ(c.header.frame_id, e[4]);
      EXPECT_EQ(std::to_string(c.width), e[5]);
      EXPECT_EQ(std::to_string(c.point_step), e[6]);
      EXPECT_EQ(c.height, 1u);
      EXPECT_TRUE(c.is_dense);
      const auto points = test::aevaPoints(c);
      for (const auto& [p, at] : {std::pair{points.front(), 7}, std::pair{points.back(), 15}}) {
        const std::array<double, 6> got = {p.x, p.y, p.z, p.intensity, p.reflectivity, p.velocity};
        for (std::size_t k = 0; k < 6; ++k)
          EXPECT_EQ(got[k], num(e[at + k])) << "point value " << k;
        EXPECT_EQ(std::to_string(p.time_offset_ns), e[at + 6]);
        EXPECT_EQ(std::to_string(p.line_index), e[at + 7]);
      }
    } else {
      ASSERT_EQ(topic.type, kTFMessageType);
      const TFMessage tf = decodeTFMessage(m.data);
      ASSERT_EQ(std::to_string(tf.transforms.size()), e[2]);
      for (std::size_t t = 0; t < tf.transforms.size(); ++t) {
        const std::size_t at = 3 + t * 11;
        const TransformStamped& s = tf.transforms[t];
        EXPECT_EQ(s.header.frame_id, e[at + 2]);
        EXPECT_EQ(s.child_frame_id, e[at + 3]);
        const std::array<double, 7> got = {s.translation.x, s.translation.y, s.translation.z,
                                           s.rotation.x,    s.rotation.y,    s.rotation.z,
                                           s.rotation.w};
        for (std::size_t k = 0; k < 7; ++k) EXPECT_EQ(got[k], num(e[at + 4 + k]));
      }
    }
  }
  EXPECT_EQ(i, expected.size());
}

TEST(Ros2Recordings, EveryRecordingReadsToTheSameMessages) {
  const auto reference = test::describeAll(*openRecording(fixture("imu_cloud.mcap")));
  ASSERT_EQ(reference.size(), 84u);
  for (const std::string& name : kRecordings) {
    const auto r = openRecording(fixture(name));
    EXPECT_TRUE(r->ordered()) << name;
    EXPECT_TRUE(r->warnings().empty()) << name << ": " << r->warnings()[0];
    const auto lines = test::describeAll(*r);
    ASSERT_EQ(lines.size(), reference.size()) << name;
    for (std::size_t i = 0; i < lines.size(); ++i)
      ASSERT_EQ(lines[i], reference[i]) << name << " message " << i;
  }
}

// The generator's motion: v_b = (2, 0, 0) m/s, w_b = (0, 0, 0.5) rad/s, z up. With the LiDAR's
// pose from /tf_static, every point's Doppler is its range rate -d . R_bl^T (v_b + w_b x p_bl),
// and the IMU measures the specific force w_b x v_b + (0, 0, 9.81).
TEST(Ros2Recordings, DopplerAndSpecificForceAreThoseOfTheMotion) {
  const double v_b[3] = {2.0, 0.0, 0.0};
  for (const std::string& name : {std::string("imu_cloud_be.mcap"), std::string("imu_cloud_db3")}) {
    const auto r = openRecording(fixture(name));
    const std::size_t imu_topic = r->topic("/imu/data", kImuType);
    const std::size_t cloud_topic = r->topic("/aeva/AeriesII/point_cloud_frame", kPointCloud2Type);
    const std::size_t tf_topic = r->topic("/tf_static", kTFMessageType);
    Message m;
    double R_bl[3][3] = {};
    double p_bl[3] = {};
    double w_b[3] = {};
    bool have_tf = false;
    std::size_t points = 0;
    while (r->next(m)) {
      if (m.topic == tf_topic) {
        for (const TransformStamped& t : decodeTFMessage(m.data).transforms) {
          if (t.header.frame_id != "imu_link" || t.child_frame_id != "aeva_link") continue;
          const Quaternion& q = t.rotation;
          const double R[3][3] = {{1 - 2 * (q.y * q.y + q.z * q.z), 2 * (q.x * q.y - q.z * q.w),
                                   2 * (q.x * q.z + q.y * q.w)},
                                  {2 * (q.x * q.y + q.z * q.w), 1 - 2 * (q.x * q.x + q.z * q.z),
                                   2 * (q.y * q.z - q.x * q.w)},
                                  {2 * (q.x * q.z - q.y * q.w), 2 * (q.y * q.z + q.x * q.w),
                                   1 - 2 * (q.x * q.x + q.y * q.y)}};
          std::copy(&R[0][0], &R[0][0] + 9, &R_bl[0][0]);
          p_bl[0] = t.translation.x;
          p_bl[1] = t.translation.y;
          p_bl[2] = t.translation.z;
          have_tf = true;
        }
      } else if (m.topic == imu_topic) {
        const Imu imu = decodeImu(m.data);
        w_b[0] = imu.angular_velocity.x;
        w_b[1] = imu.angular_velocity.y;
        w_b[2] = imu.angular_velocity.z;
        const double a[3] = {w_b[1] * v_b[2] - w_b[2] * v_b[1], w_b[2] * v_b[0] - w_b[0] * v_b[2],
                             w_b[0] * v_b[1] - w_b[1] * v_b[0] + 9.81};
        EXPECT_NEAR(imu.linear_acceleration.x, a[0], 1e-12);
        EXPECT_NEAR(imu.linear_acceleration.y, a[1], 1e-12);
        EXPECT_NEAR(imu.linear_acceleration.z, a[2], 1e-12);
        // Yaw = 0.5 t from the first stamp.
        const double t = (imu.header.stamp.nanoseconds() - 1700000000000000000) * 1e-9;
        EXPECT_NEAR(imu.orientation.z, std::sin(0.25 * t), 1e-12);
      } else if (m.topic == cloud_topic) {
        ASSERT_TRUE(have_tf) << "the extrinsics come first";
        const double u[3] = {v_b[0] + w_b[1] * p_bl[2] - w_b[2] * p_bl[1],
                             v_b[1] + w_b[2] * p_bl[0] - w_b[0] * p_bl[2],
                             v_b[2] + w_b[0] * p_bl[1] - w_b[1] * p_bl[0]};
        double v_l[3];
        for (int c = 0; c < 3; ++c)
          v_l[c] = R_bl[0][c] * u[0] + R_bl[1][c] * u[1] + R_bl[2][c] * u[2];
        for (const test::AevaPoint& p : test::aevaPoints(decodePointCloud2(m.data))) {
          const double range = std::sqrt(double{p.x} * p.x + double{p.y} * p.y + double{p.z} * p.z);
          const double doppler = -(p.x * v_l[0] + p.y * v_l[1] + p.z * v_l[2]) / range;
          EXPECT_NEAR(p.velocity, doppler, 1e-6);  // float32 storage of |v| <= 2 m/s
          EXPECT_GE(p.time_offset_ns, 0);
          EXPECT_LT(p.time_offset_ns, 100000000);
          ++points;
        }
      }
    }
    EXPECT_EQ(points, 3u * 128u) << name;
  }
}

// Any window (and any topic subset) reads exactly the messages that reading everything and
// skipping the rest reads: with the MCAP chunk indexes, the scan of a file without summary, chunks
// out of log-time order, the SQLite timestamp index, and across split files.
TEST(Ros2Recordings, AWindowReadsWhatSkippingReads) {
  for (const char* name : {"imu_cloud.mcap", "imu_cloud_zstd.mcap", "imu_cloud_nosummary.mcap",
                           "imu_cloud_killed.mcap", "imu_cloud_unchunked.mcap", "imu_cloud_db3",
                           "imu_cloud.db3", "imu_cloud_mcap"}) {
    const auto r = openRecording(fixture(name));
    std::vector<std::pair<std::int64_t, std::string>> all;
    std::vector<std::string> all_lines;
    {
      r->start({});
      Message m;
      while (r->next(m)) {
        all.emplace_back(m.log_time, r->topics()[m.topic].name);
        all_lines.push_back(test::describeMessage(*r, m));
      }
    }
    ASSERT_FALSE(all.empty());
    const std::int64_t first = all.front().first, last = all.back().first;
    // Windows at message times (bounds included), between them, and outside the recording.
    const std::vector<std::pair<std::int64_t, std::int64_t>> windows = {
        {first, last},
        {all[10].first, all[40].first},
        {all[40].first + 1, all[41].first - 1},
        {all[20].first + 1, last},
        {last, last + 1000},
        {first - 1000, first},
        {last + 1, last + 2},
        {all[30].first, all[30].first}};
    const std::vector<std::vector<std::string>> subsets = {
        {}, {"/imu/data"}, {"/aeva/AeriesII/point_cloud_frame", "/tf_static"}};
    for (const auto& [start, end] : windows) {
      for (const auto& subset : subsets) {
        ReadOptions o;
        o.start = start;
        o.end = end;
        for (const std::string& t : subset) o.topics.push_back(r->topic(t));
        std::vector<std::string> expected;
        for (std::size_t i = 0; i < all.size(); ++i) {
          const bool topic_ok = subset.empty() || std::find(subset.begin(), subset.end(),
                                                            all[i].second) != subset.end();
          if (all[i].first >= start && all[i].first <= end && topic_ok)
            expected.push_back(all_lines[i]);
        }
        EXPECT_EQ(test::describeAll(*r, o), expected)
            << name << " window [" << start << ", " << end << "], " << subset.size() << " topic(s)";
      }
    }
  }
}

}  // namespace
}  // namespace freeinit::ros2
