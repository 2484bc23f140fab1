// The MCAP reader on files written by the MCAP project's own writer (fixtures/generate.mjs):
// indexed and scanned opening, truncation anywhere, corrupt and unsupported content, what a
// window costs, the limits.
#include <freeinit/ros2/mcap_reader.h>
#include <freeinit/ros2/message_decoding.h>
#include <freeinit/ros2/open_recording.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "recording_content.h"

namespace freeinit::ros2 {
namespace {

namespace fs = std::filesystem;
using test::fixture;
using ::testing::HasSubstr;
using ::testing::StartsWith;

constexpr std::int64_t kT0 = 1700000000000000000;  // [ns] the fixtures' first header stamp

std::vector<std::uint8_t> readFile(const std::string& path) {
  const std::string bytes = test::fileBytes(path);
  return {bytes.begin(), bytes.end()};
}

std::string writeTemp(const std::string& name, const std::vector<std::uint8_t>& bytes) {
  const fs::path dir = fs::temp_directory_path() / "freeinit_test_mcap_reader";
  fs::create_directories(dir);
  const std::string path = (dir / name).string();
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()),
             static_cast<std::streamsize>(bytes.size()));
  return path;
}

// The "# chunks of imu_cloud.mcap (offset length): ..." line of expected.txt.
std::vector<std::pair<std::uint64_t, std::uint64_t>> referenceChunks() {
  std::ifstream in(fixture("expected.txt"));
  std::string line;
  const std::string key = "# chunks of imu_cloud.mcap (offset length):";
  while (std::getline(in, line))
    if (line.rfind(key, 0) == 0) {
      std::istringstream s(line.substr(key.size()));
      std::vector<std::pair<std::uint64_t, std::uint64_t>> chunks;
      std::uint64_t offset, length;
      while (s >> offset >> length) chunks.emplace_back(offset, length);
      return chunks;
    }
  return {};
}

TEST(McapReader, OpensByTheSummary) {
  McapReader r(fixture("imu_cloud.mcap"));
  EXPECT_TRUE(r.indexed());
  EXPECT_TRUE(r.ordered());
  EXPECT_TRUE(r.warnings().empty());
  EXPECT_EQ(r.kind(), "an MCAP file (ROS 2)");
  EXPECT_EQ(r.chunkCount(), referenceChunks().size());
  EXPECT_EQ(r.topicList(),
            "/tf_static (tf2_msgs/msg/TFMessage), /imu/data (sensor_msgs/msg/Imu), "
            "/aeva/AeriesII/point_cloud_frame (sensor_msgs/msg/PointCloud2)");
  const std::size_t imu = r.topic("/imu/data", kImuType);
  EXPECT_EQ(r.topics()[imu].message_count, 80u);
  EXPECT_EQ(r.topics()[imu].encoding, "cdr");
  EXPECT_EQ(r.topics()[r.topic("/aeva/AeriesII/point_cloud_frame", kPointCloud2Type)].message_count,
            3u);
  ASSERT_TRUE(r.timeRange());
  EXPECT_EQ(r.timeRange()->first, kT0 + 500000);
  EXPECT_EQ(r.timeRange()->last, kT0 + 396000000);
  // Opening read the ends of the file only: magic, footer, summary.
  EXPECT_LT(r.bytesRead(), fs::file_size(fixture("imu_cloud.mcap")) / 10);
}

TEST(McapReader, ScansAFileWithoutSummary) {
  McapReader r(fixture("imu_cloud_nosummary.mcap"));
  EXPECT_FALSE(r.indexed());
  EXPECT_TRUE(r.ordered());
  EXPECT_TRUE(r.warnings().empty()) << r.warnings()[0];  // closed properly, just no summary
  EXPECT_EQ(r.topics()[r.topic("/imu/data")].message_count, 80u);
  EXPECT_EQ(r.topics()[r.topic("/tf_static")].message_count, 1u);
  ASSERT_TRUE(r.timeRange());
  EXPECT_EQ(r.timeRange()->first, kT0 + 500000);
  EXPECT_EQ(r.timeRange()->last, kT0 + 396000000);
}

// Messages outside chunks: no chunk index to merge by, so the file is read in its own order.
TEST(McapReader, ReadsMessagesOutsideChunksInFileOrder) {
  McapReader r(fixture("imu_cloud_unchunked.mcap"));
  EXPECT_FALSE(r.indexed());
  EXPECT_FALSE(r.ordered());
  EXPECT_EQ(r.chunkCount(), 0u);
  ASSERT_EQ(r.warnings().size(), 1u);
  EXPECT_EQ(r.warnings()[0], "messages outside chunks: read in file order, not sorted by log time");
  EXPECT_EQ(r.topics()[r.topic("/imu/data")].message_count, 80u);
  // Written in log-time order, so file order is the reference's order.
  EXPECT_EQ(test::describeAll(r), test::describeAll(*openRecording(fixture("imu_cloud.mcap"))));
}

TEST(McapReader, ReadsWhatIsWholeOfAKilledRecording) {
  const auto reference = test::describeAll(*openRecording(fixture("imu_cloud.mcap")));
  const auto chunks = referenceChunks();
  McapReader r(fixture("imu_cloud_killed.mcap"));
  EXPECT_FALSE(r.indexed());
  ASSERT_EQ(r.warnings().size(), 1u);
  // Record 15: after the header, five chunks and their eight message indexes (one per channel).
  EXPECT_EQ(r.warnings()[0], "the file ends at byte 29456, inside record 15 (Chunk at byte " +
                                 std::to_string(chunks[5].first) + "): read what is whole");
  const auto lines = test::describeAll(r);
  // Chunks 1-5 are whole and the sixth is cut: the messages of the first five, in order.
  ASSERT_GT(lines.size(), 30u);
  ASSERT_LT(lines.size(), reference.size());
  EXPECT_EQ(lines, std::vector<std::string>(reference.begin(), reference.begin() + lines.size()));
  EXPECT_EQ(r.topics()[r.topic("/imu/data")].message_count, lines.size() - 3);  // tf + 2 clouds
}

// Cut anywhere, a file opens (past its magic) and reads a prefix of its messages, with a warning
// unless the cut falls in the summary; never an error.
TEST(McapReader, ReadsAPrefixOfAFileCutAnywhere) {
  // Each message as its topic, log time and bytes.
  const auto raw = [](Recording& r) {
    std::vector<std::string> v;
    Message m;
    r.start({});
    while (r.next(m))
      v.push_back(std::to_string(m.topic) + " " + std::to_string(m.log_time) + " " +
                  std::string(m.data.begin(), m.data.end()));
    return v;
  };
  for (const char* name :
       {"imu_cloud.mcap", "imu_cloud_nosummary.mcap", "imu_cloud_unchunked.mcap"}) {
    const auto whole = readFile(fixture(name));
    const auto reference = raw(*openRecording(fixture(name)));
    std::size_t with_warning = 0;
    for (std::size_t cut = 8; cut < whole.size(); cut += 89) {
      const std::string path = writeTemp(
          "cut.mcap", std::vector<std::uint8_t>(whole.begin(),
                                                whole.begin() + static_cast<std::ptrdiff_t>(cut)));
      McapReader r(path);
      const auto messages = raw(r);
      ASSERT_LE(messages.size(), reference.size()) << name << " cut at " << cut;
      ASSERT_TRUE(std::equal(messages.begin(), messages.end(), reference.begin()))
          << name << " cut at " << cut;
      bool whole_part = false;
      for (const std::string& w : r.warnings())
        whole_part = whole_part || w.find("read what is whole") != std::string::npos;
      with_warning += whole_part ? 1 : 0;
    }
    // Every cut before the summary warns (the summary is a small part of each file).
    EXPECT_GT(with_warning, whole.size() / 89 * 3 / 4) << name;
  }
}

TEST(McapReader, RefusesAFileWithoutTheMagic) {
  auto bytes = readFile(fixture("imu_cloud.mcap"));
  bytes[4] = 'X';
  const std::string path = writeTemp("bad_magic.mcap", bytes);
  EXPECT_THAT([&] { McapReader r(path); },
              ::testing::ThrowsMessage<RecordingError>(
                  path + ": an MCAP file (ROS 2): the file does not start with the MCAP magic "
                         "(\\x89MCAP0\\r\\n)"));
  EXPECT_EQ(identifyRecording(path), RecordingKind::kUnknown);
  EXPECT_THAT(
      [&] { openRecording(path); },
      ::testing::ThrowsMessage<RecordingError>(
          path +
          ": not a ROS 2 recording: it starts with 89 4d 43 41 58 30 0d 0a (\".MCAX0..\"; an "
          "MCAP file starts with \\x89MCAP0\\r\\n, a rosbag2 .db3 with 'SQLite format 3')"));
}

TEST(McapReader, NamesAnUnsupportedCompression) {
  const std::string path = fixture("tf_bz2.mcap");
  EXPECT_THAT(
      [&] { openRecording(path); },
      ::testing::ThrowsMessage<RecordingError>(
          path + ": an MCAP file (ROS 2): chunk 1 (at byte 64): compressed with 'bz2', which is "
                 "not supported (none, zstd, lz4 are)"));
  // The same without the summary: found by the scan.
  auto bytes = readFile(path);
  const std::string cut =
      writeTemp("bz2_cut.mcap", std::vector<std::uint8_t>(bytes.begin(), bytes.end() - 100));
  EXPECT_THAT([&] { openRecording(cut); },
              ::testing::ThrowsMessage<RecordingError>(HasSubstr(
                  "chunk 1 (record 2 at byte 64): compressed with 'bz2', which is not supported")));
}

TEST(McapReader, RefusesACorruptChunk) {
  const auto chunks = referenceChunks();
  auto bytes = readFile(fixture("imu_cloud.mcap"));
  // The last byte of chunk 3: inside the data of its last message.
  const std::size_t at = chunks[2].first + chunks[2].second - 1;
  bytes[at] ^= 0x5A;
  const std::string path = writeTemp("corrupt.mcap", bytes);
  McapReader r(path);
  EXPECT_THAT(
      [&] { test::describeAll(r); },
      ::testing::ThrowsMessage<RecordingError>(
          path + ": an MCAP file (ROS 2): chunk 3 (at byte " + std::to_string(chunks[2].first) +
          "): its records do not match their CRC (a corrupt file)"));
  // Without the check the reader returns the bytes as they are.
  ReaderLimits no_crc;
  no_crc.verify_crc = false;
  McapReader unchecked(path, no_crc);
  EXPECT_EQ(test::stamps(unchecked).size(), 84u);
}

TEST(McapReader, RefusesAChunkIndexPointingElsewhere) {
  const auto chunks = referenceChunks();
  auto bytes = readFile(fixture("imu_cloud.mcap"));
  // Overwrite the opcode of chunk 2's record: its index now points at no chunk.
  bytes[chunks[1].first] = 0x0C;
  const std::string path = writeTemp("bad_index.mcap", bytes);
  McapReader r(path);
  EXPECT_THAT(
      [&] { test::describeAll(r); },
      ::testing::ThrowsMessage<RecordingError>(
          path + ": an MCAP file (ROS 2): chunk 2 (at byte " + std::to_string(chunks[1].first) +
          "): expected a Chunk record of " + std::to_string(chunks[1].second) + " bytes at byte " +
          std::to_string(chunks[1].first) + ", found Metadata of " +
          std::to_string(chunks[1].second - 9)));
}

TEST(McapReader, BoundsChunksByTheLimit) {
  ReaderLimits small;
  small.max_chunk_bytes = 3000;
  McapReader indexed(fixture("imu_cloud.mcap"), small);  // opening reads no chunk
  EXPECT_THAT([&] { test::describeAll(indexed); },
              ::testing::ThrowsMessage<RecordingError>(HasSubstr(
                  "): 4329 bytes, more than the 3000 accepted (ReaderLimits::max_chunk_bytes)")));
  EXPECT_THAT([&] { McapReader scanned(fixture("imu_cloud_nosummary.mcap"), small); },
              ::testing::ThrowsMessage<RecordingError>(HasSubstr("decompresses to")));
}

// Chunks overlapping in time are held together while their messages are merged: bounded too.
TEST(McapReader, BoundsTheChunksHeldAtOnce) {
  ReaderLimits limits;
  limits.max_loaded_bytes = 8000;  // one chunk of these files, not two
  McapReader in_order(fixture("imu_cloud.mcap"), limits);
  EXPECT_EQ(test::stamps(in_order).size(), 84u);
  McapReader overlapping(fixture("imu_cloud_zstd.mcap"), limits);  // clouds written late
  EXPECT_THAT(
      [&] { test::stamps(overlapping); },
      ::testing::ThrowsMessage<RecordingError>(HasSubstr(
          "with the chunks overlapping it in time, more than 8000 bytes at once "
          "(ReaderLimits::max_loaded_bytes): the file's chunks are far from log-time order")));
}

// A window of the last 30 ms of an indexed file reads a fraction of it: the chunks that overlap.
TEST(McapReader, AWindowCostsTheWindow) {
  McapReader r(fixture("imu_cloud.mcap"));
  const std::uint64_t size = fs::file_size(fixture("imu_cloud.mcap"));
  const std::uint64_t opened = r.bytesRead();
  ReadOptions window;
  window.start = kT0 + 370000000;
  const auto late = test::stamps(r, window);
  ASSERT_FALSE(late.empty());
  const std::uint64_t window_cost = r.bytesRead() - opened;
  test::stamps(r);
  const std::uint64_t whole_cost = r.bytesRead() - opened - window_cost;
  EXPECT_LT(window_cost, size / 4);
  EXPECT_GT(whole_cost, size * 8 / 10);
  // Only /tf_static: the chunks without it (all but the first) are not read.
  ReadOptions tf_only;
  tf_only.topics = {r.topic("/tf_static")};
  const std::uint64_t before = r.bytesRead();
  EXPECT_EQ(test::stamps(r, tf_only).size(), 1u);
  EXPECT_LT(r.bytesRead() - before, whole_cost / 5);
}

TEST(McapReader, TopicErrorsListWhatThereIs) {
  McapReader r(fixture("imu_cloud_lz4.mcap"));
  const std::string path = fixture("imu_cloud_lz4.mcap");
  EXPECT_THAT(
      [&] { r.topic("/imu", kImuType); },
      ::testing::ThrowsMessage<RecordingError>(
          path + ": topic /imu not found; the recording has: /tf_static (tf2_msgs/msg/TFMessage), "
                 "/imu/data (sensor_msgs/msg/Imu), /aeva/AeriesII/point_cloud_frame "
                 "(sensor_msgs/msg/PointCloud2)"));
  EXPECT_THAT(
      [&] { r.topic("/imu/data", kPointCloud2Type); },
      ::testing::ThrowsMessage<RecordingError>(
          path +
          ": topic /imu/data has type sensor_msgs/msg/Imu, expected sensor_msgs/msg/PointCloud2"));
  const std::string json = fixture("json_topic.mcap");
  const auto other = openRecording(json);
  EXPECT_THAT([&] { other->topic("/status"); },
              ::testing::ThrowsMessage<RecordingError>(
                  json + ": topic /status is encoded as 'json'; only 'cdr' (ROS 2) is read"));
  EXPECT_THAT(
      [&] {
        r.start({0, 1, {7}});
      },
      ::testing::ThrowsMessage<RecordingError>(path + ": topic index 7 out of range (3 topics)"));
}

}  // namespace
}  // namespace freeinit::ros2
