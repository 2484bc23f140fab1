// The CDR decoder: encapsulation, alignment, byte order, bounds. Messages are built here byte by
// byte (the recordings of test_ros2_recordings.cpp come from an independent CDR writer) and taken
// from a fixture recording to be cut at every length.
#include <freeinit/ros2/message_decoding.h>
#include <freeinit/ros2/open_recording.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "recording_content.h"

namespace freeinit::ros2 {
namespace {

using ::testing::HasSubstr;

// Writes CDR by hand: values aligned to their size counted from after the 4-byte header.
class Bytes {
 public:
  explicit Bytes(bool big_endian = false) : be_(big_endian) {
    b_ = {0x00, static_cast<std::uint8_t>(big_endian ? 0x00 : 0x01), 0x00, 0x00};
  }
  template <class T>
  Bytes& put(T v) {
    while ((b_.size() - 4) % sizeof(T) != 0) b_.push_back(0xEE);  // padding, any value
    std::uint8_t raw[sizeof(T)];
    std::memcpy(raw, &v, sizeof(T));
    for (std::size_t i = 0; i < sizeof(T); ++i) b_.push_back(raw[be_ ? sizeof(T) - 1 - i : i]);
    return *this;
  }
  Bytes& str(const std::string& s) {
    put<std::uint32_t>(static_cast<std::uint32_t>(s.size() + 1));
    b_.insert(b_.end(), s.begin(), s.end());
    b_.push_back(0);
    return *this;
  }
  Bytes& raw(std::initializer_list<std::uint8_t> bytes) {
    b_.insert(b_.end(), bytes);
    return *this;
  }
  const std::vector<std::uint8_t>& get() const { return b_; }

 private:
  bool be_;
  std::vector<std::uint8_t> b_;
};

Bytes imuBytes(bool big_endian) {
  Bytes b(big_endian);
  b.put<std::int32_t>(1700000000).put<std::uint32_t>(5000).str("imu");
  for (int i = 0; i < 4; ++i) b.put<double>(0.5 * i);  // orientation
  for (int i = 0; i < 9; ++i) b.put<double>(i);
  for (int i = 0; i < 3; ++i) b.put<double>(0.1 * (i + 1));  // angular velocity
  for (int i = 0; i < 9; ++i) b.put<double>(-i);
  for (int i = 0; i < 3; ++i) b.put<double>(10.0 * (i + 1));  // linear acceleration
  for (int i = 0; i < 9; ++i) b.put<double>(2.0 * i);
  return b;
}

TEST(CdrDecoding, ImuInEitherByteOrder) {
  for (const bool be : {false, true}) {
    const Imu m = decodeImu(imuBytes(be).get());
    EXPECT_EQ(m.header.stamp.sec, 1700000000);
    EXPECT_EQ(m.header.stamp.nanosec, 5000u);
    EXPECT_EQ(m.header.stamp.nanoseconds(), 1700000000000005000);
    EXPECT_EQ(m.header.frame_id, "imu");
    EXPECT_EQ(m.orientation.w, 1.5);
    EXPECT_EQ(m.orientation_covariance[8], 8.0);
    EXPECT_EQ(m.angular_velocity.z, 0.30000000000000004);
    EXPECT_EQ(m.angular_velocity_covariance[4], -4.0);
    EXPECT_EQ(m.linear_acceleration.y, 20.0);
    EXPECT_EQ(m.linear_acceleration_covariance[1], 2.0);
  }
}

TEST(CdrDecoding, AlignsFromAfterTheEncapsulationHeader) {
  // frame_id "imu" (4 + 4 bytes) ends at byte 16 of the payload: the first float64 needs no
  // padding. With "imu1" (4 + 5) it ends at 17 and the float64 starts at 24 (7 bytes of padding).
  Bytes b;
  b.put<std::int32_t>(1).put<std::uint32_t>(2).str("imu1");
  for (int i = 0; i < 37; ++i) b.put<double>(i);
  ASSERT_EQ(b.get().size(), 4u + 24u + 37u * 8u);
  const Imu m = decodeImu(b.get());
  EXPECT_EQ(m.header.frame_id, "imu1");
  EXPECT_EQ(m.orientation.x, 0.0);
  EXPECT_EQ(m.linear_acceleration_covariance[8], 36.0);
}

TEST(CdrDecoding, RefusesOtherEncapsulations) {
  const std::vector<std::uint8_t> short_message{0x00, 0x01, 0x00};
  EXPECT_THAT([&] { decodeImu(short_message); },
              ::testing::ThrowsMessage<CdrError>(
                  HasSubstr("shorter than its 4-byte encapsulation header")));
  std::vector<std::uint8_t> m = imuBytes(false).get();
  m[1] = 0x03;
  EXPECT_THAT([&] { decodeImu(m); },
              ::testing::ThrowsMessage<CdrError>(
                  "encapsulation 00 03 (PL_CDR_LE, a parameter list) is not supported: only plain "
                  "CDR (00 00 big endian, 00 01 little endian)"));
  m[1] = 0x07;
  EXPECT_THAT([&] { decodeImu(m); },
              ::testing::ThrowsMessage<CdrError>(HasSubstr("00 07 (CDR2_LE, XCDR version 2)")));
}

TEST(CdrDecoding, StringsNeedTheirBytesAndTheirNul) {
  Bytes no_nul;
  no_nul.put<std::int32_t>(1).put<std::uint32_t>(2).put<std::uint32_t>(3).raw({'i', 'm', 'u'});
  EXPECT_THAT([&] { decodeImu(no_nul.get()); },
              ::testing::ThrowsMessage<CdrError>("header.frame_id: a string not ended by its NUL"));
  Bytes too_long;
  too_long.put<std::int32_t>(1).put<std::uint32_t>(2).put<std::uint32_t>(4000000000u).raw({'a', 0});
  EXPECT_THAT([&] { decodeImu(too_long.get()); },
              ::testing::ThrowsMessage<CdrError>(
                  "header.frame_id: a string of 4000000000 bytes, only 2 left in the message"));
}

TEST(CdrDecoding, SequenceCountsAreBoundedByTheBytesLeft) {
  // A PointCloud2 declaring 2^32 - 1 fields, or a data array of 4 GB, in a few bytes: refused
  // before anything is allocated.
  Bytes fields;
  fields.put<std::int32_t>(1)
      .put<std::uint32_t>(2)
      .str("l")
      .put<std::uint32_t>(1)
      .put<std::uint32_t>(8);
  fields.put<std::uint32_t>(0xFFFFFFFFu).raw({0, 0, 0, 0});
  EXPECT_THAT([&] { decodePointCloud2(fields.get()); },
              ::testing::ThrowsMessage<CdrError>(
                  "PointCloud2.fields: a sequence of 4294967295 elements, of at least 13 bytes "
                  "each, only 4 bytes left in the message"));
  Bytes data;
  data.put<std::int32_t>(1).put<std::uint32_t>(2).str("l").put<std::uint32_t>(1).put<std::uint32_t>(
      8);
  data.put<std::uint32_t>(0).put<std::uint8_t>(0).put<std::uint32_t>(4).put<std::uint32_t>(32);
  data.put<std::uint32_t>(0xFFFFFFF0u).raw({1, 2, 3});
  EXPECT_THAT(
      [&] { decodePointCloud2(data.get()); },
      ::testing::ThrowsMessage<CdrError>(HasSubstr("PointCloud2.data: a sequence of 4294967280")));
  Bytes transforms;
  transforms.put<std::uint32_t>(1000).raw({0, 0, 0, 0});
  EXPECT_THAT(
      [&] { decodeTFMessage(transforms.get()); },
      ::testing::ThrowsMessage<CdrError>(HasSubstr("TFMessage.transforms: a sequence of 1000")));
}

TEST(CdrDecoding, BooleansAreZeroOrOne) {
  Bytes b;
  b.put<std::int32_t>(1).put<std::uint32_t>(2).str("l").put<std::uint32_t>(1).put<std::uint32_t>(0);
  b.put<std::uint32_t>(0).put<std::uint8_t>(7);
  EXPECT_THAT([&] { decodePointCloud2(b.get()); },
              ::testing::ThrowsMessage<CdrError>("PointCloud2.is_bigendian: boolean of value 7"));
}

TEST(CdrDecoding, PointCloud2WithAllItsFields) {
  Bytes b(true);
  b.put<std::int32_t>(7).put<std::uint32_t>(8).str("aeva").put<std::uint32_t>(2).put<std::uint32_t>(
      3);
  b.put<std::uint32_t>(2).str("x").put<std::uint32_t>(0).put<std::uint8_t>(7).put<std::uint32_t>(1);
  b.str("line_index").put<std::uint32_t>(4).put<std::uint8_t>(2).put<std::uint32_t>(1);
  b.put<std::uint8_t>(1).put<std::uint32_t>(5).put<std::uint32_t>(15);
  b.put<std::uint32_t>(30);
  for (int i = 0; i < 30; ++i) b.put<std::uint8_t>(static_cast<std::uint8_t>(i));
  b.put<std::uint8_t>(0);
  const PointCloud2 c = decodePointCloud2(b.get());
  EXPECT_EQ(c.header.frame_id, "aeva");
  EXPECT_EQ(c.height, 2u);
  EXPECT_EQ(c.width, 3u);
  ASSERT_EQ(c.fields.size(), 2u);
  EXPECT_EQ(c.fields[1].name, "line_index");
  EXPECT_EQ(c.fields[1].offset, 4u);
  EXPECT_EQ(c.fields[1].datatype, 2);
  EXPECT_TRUE(c.is_bigendian);
  EXPECT_EQ(c.point_step, 5u);
  EXPECT_EQ(c.row_step, 15u);
  ASSERT_EQ(c.data.size(), 30u);
  EXPECT_EQ(c.data[29], 29);
  EXPECT_FALSE(c.is_dense);
}

// Every message of the reference recording, cut at every length short of its end, is refused
// with a CdrError (the last field is never optional), and decodes whole.
TEST(CdrDecoding, EveryTruncationOfRealMessagesIsRefused) {
  const auto r = openRecording(test::fixture("imu_cloud.mcap"));
  Message m;
  std::size_t checked = 0;
  while (r->next(m)) {
    if (checked++ % 10 != 0 && r->topics()[m.topic].type == kImuType) continue;  // every 10th IMU
    const std::string& type = r->topics()[m.topic].type;
    const auto decode = [&](std::size_t n) {
      if (type == kImuType) decodeImu(m.data.data(), n);
      if (type == kPointCloud2Type) decodePointCloud2(m.data.data(), n);
      if (type == kTFMessageType) decodeTFMessage(m.data.data(), n);
    };
    ASSERT_NO_THROW(decode(m.data.size())) << type;
    for (std::size_t n = 0; n < m.data.size(); ++n)
      ASSERT_THROW(decode(n), CdrError) << type << " " << n;
  }
  EXPECT_GT(checked, 80u);
}

}  // namespace
}  // namespace freeinit::ros2
