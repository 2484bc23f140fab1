// The bag guard (ros1/bag_guard.h) against bags corrupted one field at a time: each check names
// the byte and what is wrong, and readBag reports it before librosbag sees the file. Valid bags
// (uncompressed, lz4, bz2) pass. Bags are written in-test with the project's bag writer.
#include <freeinit/ros1/bag_guard.h>
#include <freeinit/ros1/bag_reader.h>
#include <freeinit/ros1/bag_writer.h>
#include <freeinit/ros1/cloud_codec.h>
#include <gtest/gtest.h>
#include <ros/serialization.h>
#include <sensor_msgs/PointCloud2.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>

#include "ros_test_files.h"

using namespace freeinit;
using namespace freeinit::ros1;
namespace fs = std::filesystem;

namespace {

std::string dir() { return test::testFolder("freeinit_bag_guard_tests"); }

// 40 IMU samples and 3 frames of 10 points, release layout.
std::string validBag(const std::string& path,
                     BagWriteOptions::Compression c = BagWriteOptions::Compression::kNone) {
  std::vector<ImuSample> imu;
  for (int k = 0; k < 40; ++k) {
    ImuSample s;
    s.t = 1700000000.0 + 0.005 * k;
    s.accel = Vec3(0, 0, 9.81);
    imu.push_back(s);
  }
  std::vector<LidarFrame> frames;
  for (int f = 0; f < 3; ++f) {
    LidarFrame fr;
    fr.stamp = 1700000000.01 + 0.05 * f;
    for (int i = 0; i < 10; ++i) {
      DopplerPoint p;
      p.p_l = Eigen::Vector3f(3.0f + i, 1, 0.5f);
      p.time_offset = 0.001f * i;
      fr.points.push_back(p);
    }
    frames.push_back(fr);
  }
  BagWriteOptions o;
  o.compression = c;
  o.lidar_publish_delay = 0.02;
  writeBag(path, imu, frames, o);
  return path;
}

using Bytes = std::vector<std::uint8_t>;
Bytes load(const std::string& p) {
  std::ifstream in(p, std::ios::binary);
  return Bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}
std::string save(const std::string& p, const Bytes& b) {
  std::ofstream(p, std::ios::binary)
      .write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
  return p;
}
std::uint32_t u32(const Bytes& b, std::size_t at) {
  std::uint32_t v;
  std::memcpy(&v, &b[at], 4);
  return v;
}
void put32(Bytes& b, std::size_t at, std::uint32_t v) { std::memcpy(&b[at], &v, 4); }

// The top-level records of a bag, as the format defines them (independent of the guard's code).
struct Rec {
  std::size_t at, data_at;
  std::uint32_t data_len;
  std::uint8_t op;
  std::map<std::string, std::size_t> field;  // name -> offset of its value in the file
};
std::vector<Rec> records(const Bytes& b) {
  std::vector<Rec> out;
  std::size_t at = 13;
  while (at + 4 <= b.size()) {
    Rec r;
    r.at = at;
    const std::uint32_t hl = u32(b, at);
    std::size_t p = at + 4;
    while (p < at + 4 + hl) {
      const std::uint32_t fl = u32(b, p);
      const std::string f(reinterpret_cast<const char*>(&b[p + 4]), fl);
      const std::size_t eq = f.find('=');
      r.field[f.substr(0, eq)] = p + 4 + eq + 1;
      p += 4 + fl;
    }
    r.op = b[r.field.at("op")];
    r.data_len = u32(b, p);
    r.data_at = p + 4;
    out.push_back(r);
    at = r.data_at + r.data_len;
  }
  return out;
}
// A copy: callers pass records(b), a temporary.
Rec first(const std::vector<Rec>& rs, std::uint8_t op) {
  for (const Rec& r : rs)
    if (r.op == op) return r;
  throw std::runtime_error("no record of that op");
}

std::string guardError(const std::string& path) {
  try {
    checkBagFile(path);
  } catch (const BagError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(BagGuard, ValidBagsPass) {
  const std::string d = dir();
  using C = BagWriteOptions::Compression;
  for (const auto& [name, c] :
       {std::pair{"none", C::kNone}, std::pair{"lz4", C::kLz4}, std::pair{"bz2", C::kBz2}})
    EXPECT_EQ(guardError(validBag(d + "/" + name + ".bag", c)), "") << name;
}

// A header field longer than its header: ros::Header::parse would read past the buffer.
TEST(BagGuard, HeaderFieldLongerThanItsHeader) {
  const std::string d = dir();
  Bytes b = load(validBag(d + "/ok.bag"));
  put32(b, 17, 100000);  // the file header's first field length
  const std::string e = guardError(save(d + "/bad.bag", b));
  EXPECT_CONTAINS(e, d + "/bad.bag: byte 17: record header: a field of 100000 bytes, but only");
  // readBag stops at the same check, before librosbag opens the file.
  EXPECT_THROW(
      {
        try {
          readBag(d + "/bad.bag", BagImportConfig(), {});
        } catch (const BagError& x) {
          EXPECT_EQ(std::string(x.what()), e);
          throw;
        }
      },
      BagError);
}

TEST(BagGuard, RecordLongerThanTheFile) {
  const std::string d = dir();
  Bytes b = load(validBag(d + "/ok.bag"));
  const Rec& chunk = first(records(b), 0x05);
  put32(b, chunk.data_at - 4, 0x7fffffff);  // the chunk's data length
  EXPECT_CONTAINS(guardError(save(d + "/bad.bag", b)),
                  "chunk record data of 2147483647 bytes, but only");
  Bytes t = load(d + "/ok.bag");
  t.resize(t.size() - 100);
  EXPECT_CONTAINS(guardError(save(d + "/cut.bag", t)), "(truncated bag?)");
}

// An index entry pointing into the middle of a chunk: librosbag would parse a header there.
TEST(BagGuard, IndexEntryNotAtAMessageRecord) {
  const std::string d = dir();
  Bytes b = load(validBag(d + "/ok.bag"));
  const Rec& index = first(records(b), 0x04);
  put32(b, index.data_at + 8, u32(b, index.data_at + 8) + 3);  // entry 0's offset
  EXPECT_CONTAINS(guardError(save(d + "/bad.bag", b)),
                  "index entry 0 points at byte " + std::to_string(u32(b, index.data_at + 8)) +
                      " of its chunk, which is not a message record");
}

TEST(BagGuard, UnknownConnectionAndCounts) {
  const std::string d = dir();
  Bytes b = load(validBag(d + "/ok.bag"));
  const Rec& index = first(records(b), 0x04);
  put32(b, index.field.at("conn"), 77);
  EXPECT_CONTAINS(guardError(save(d + "/conn.bag", b)),
                  "connection 77 is used but not among the index's connection records");
  b = load(d + "/ok.bag");
  put32(b, first(records(b), 0x04).field.at("count"), 1000);
  EXPECT_CONTAINS(guardError(save(d + "/count.bag", b)), "index record of 1000 entries holds");
}

TEST(BagGuard, UnindexedAndOtherFormats) {
  const std::string d = dir();
  Bytes b = load(validBag(d + "/ok.bag"));
  const std::size_t index_pos = first(records(b), 0x03).field.at("index_pos");
  std::memset(&b[index_pos], 0, 8);
  EXPECT_CONTAINS(
      guardError(save(d + "/active.bag", b)),
      "the bag is not indexed (a recording that did not finish?): run `rosbag reindex`");
  b = load(d + "/ok.bag");
  std::memcpy(&b[0], "#ROSBAG V1.2", 12);
  EXPECT_CONTAINS(guardError(save(d + "/v12.bag", b)), "a ROS bag of format 1.2");
  EXPECT_CONTAINS(guardError(save(d + "/text.bag", Bytes(100, 'x'))), "not a ROS bag");
  EXPECT_CONTAINS(guardError(d + "/missing.bag"), "cannot open as a ROS1 bag");
}

// Compressed chunks: a size field that does not match what decompresses, and an lz4 block larger
// than the frame's block size (roslz4 would copy it into a buffer of the block size).
TEST(BagGuard, CompressedChunks) {
  const std::string d = dir();
  Bytes b = load(validBag(d + "/bz2.bag", BagWriteOptions::Compression::kBz2));
  const Rec& c = first(records(b), 0x05);
  const std::uint32_t size = u32(b, c.field.at("size"));
  put32(b, c.field.at("size"), size + 1000);
  EXPECT_CONTAINS(guardError(save(d + "/bz2_size.bag", b)),
                  "bz2 chunk of declared size " + std::to_string(size + 1000) +
                      " decompresses to " + std::to_string(size) + " bytes");
  put32(b, c.field.at("size"), 0xF0000000U);
  EXPECT_CONTAINS(guardError(save(d + "/bz2_huge.bag", b)), "more than the 268435456 accepted");

  b = load(validBag(d + "/lz4.bag", BagWriteOptions::Compression::kLz4));
  const Rec& l = first(records(b), 0x05);
  put32(b, l.data_at + 7, 0x7FFFFFF0U);  // the first block's size word, after the frame header
  EXPECT_CONTAINS(guardError(save(d + "/lz4_block.bag", b)), "lz4 chunk: a block of 2147483632");
}

// The serialized-message check: lengths against the bytes left, names the field.
TEST(BagGuard, SerializedMessageLengths) {
  sensor_msgs::PointCloud2 msg;
  LidarFrame f;
  f.points.resize(3);
  encodeCloud(f, CloudLayout(), true, false, msg);
  std::vector<std::uint8_t> b(ros::serialization::serializationLength(msg));
  ros::serialization::OStream out(b.data(), static_cast<std::uint32_t>(b.size()));
  ros::serialization::serialize(out, msg);
  EXPECT_EQ(checkSerialized(RosMessage::kPointCloud2, b.data(), b.size()), b.size());
  // The field count is after the header (seq, stamp, frame_id "aeva") and height, width.
  const std::size_t count_at = 12 + 4 + 4 + 8;
  put32(b, count_at, 30000000);
  try {
    checkSerialized(RosMessage::kPointCloud2, b.data(), b.size());
    ADD_FAILURE() << "accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_CONTAINS(e.what(), "serialized sensor_msgs/PointCloud2: fields declares 30000000");
  }
  put32(b, count_at, static_cast<std::uint32_t>(msg.fields.size()));
  b.push_back(0);
  EXPECT_THROW(checkSerialized(RosMessage::kPointCloud2, b.data(), b.size()), std::runtime_error);
  EXPECT_EQ(checkSerialized(RosMessage::kPointCloud2, b.data(), b.size(), false), b.size() - 1);
  EXPECT_THROW(checkSerialized(RosMessage::kImu, b.data(), 10), std::runtime_error);
}
