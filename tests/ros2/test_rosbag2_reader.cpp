// The rosbag2 readers: .db3 files (SQLite, written here by SQLite itself through the fixture
// generator), folders with metadata.yaml, the metadata parser, and the front door's messages.
#include <freeinit/ros2/bag_metadata.h>
#include <freeinit/ros2/message_decoding.h>
#include <freeinit/ros2/open_recording.h>
#include <freeinit/ros2/rosbag2_folder_reader.h>
#include <freeinit/ros2/sqlite_bag_reader.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include "recording_content.h"

namespace freeinit::ros2 {
namespace {

namespace fs = std::filesystem;
using test::fixture;
using ::testing::HasSubstr;

constexpr std::int64_t kT0 = 1700000000000000000;  // [ns]

// A fresh temporary folder of this test.
fs::path scratch(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / "freeinit_test_rosbag2" / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string readText(const fs::path& p) { return test::fileBytes(p.string()); }

void writeText(const fs::path& p, const std::string& text) { std::ofstream(p) << text; }

void sql(const fs::path& db_path, const std::string& statements) {
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(db_path.c_str(), &db), SQLITE_OK);
  char* message = nullptr;
  const int rc = sqlite3_exec(db, statements.c_str(), nullptr, nullptr, &message);
  const std::string error = message ? message : "";
  sqlite3_free(message);
  sqlite3_close(db);
  ASSERT_EQ(rc, SQLITE_OK) << error;
}

TEST(Rosbag2Reader, ReadsASplitSqliteFolder) {
  const auto r = openRecording(fixture("imu_cloud_db3"));
  EXPECT_EQ(r->kind(), "a rosbag2 folder");
  auto& folder = dynamic_cast<Rosbag2FolderReader&>(*r);
  EXPECT_EQ(folder.metadata().version, 5);
  EXPECT_EQ(folder.metadata().storage_identifier, "sqlite3");
  ASSERT_EQ(folder.files().size(), 2u);
  EXPECT_EQ(folder.files()[1]->kind(), "a rosbag2 SQLite file (.db3)");
  EXPECT_TRUE(r->warnings().empty());
  EXPECT_EQ(r->topics()[r->topic("/imu/data", kImuType)].message_count, 80u);
  EXPECT_EQ(r->topics()[r->topic("/tf_static", kTFMessageType)].message_count, 1u);
  ASSERT_TRUE(r->timeRange());
  EXPECT_EQ(r->timeRange()->first, kT0 + 500000);
  EXPECT_EQ(r->timeRange()->last, kT0 + 396000000);
  // Across the split (at 0.2 s), in time order.
  const auto s = test::stamps(*r);
  ASSERT_EQ(s.size(), 84u);
  for (std::size_t i = 1; i < s.size(); ++i) EXPECT_LT(s[i - 1].first, s[i].first);
}

TEST(Rosbag2Reader, ReadsASingleDb3WithoutMetadata) {
  const auto r = openRecording(fixture("imu_cloud.db3"));
  EXPECT_EQ(r->kind(), "a rosbag2 SQLite file (.db3)");
  EXPECT_EQ(identifyRecording(fixture("imu_cloud.db3")), RecordingKind::kSqlite);
  EXPECT_FALSE(r->topics()[r->topic("/imu/data")].message_count);  // a .db3 does not count
  ASSERT_TRUE(r->timeRange());
  EXPECT_EQ(r->timeRange()->first, kT0 + 500000);
  EXPECT_EQ(test::stamps(*r).size(), 84u);
}

TEST(Rosbag2Reader, AWindowIsAnsweredByTheTimestampIndex) {
  SqliteBagReader r(fixture("imu_cloud.db3"));
  ReadOptions window;
  window.start = kT0 + 100000000;
  window.end = kT0 + 200000000;
  window.topics = {r.topic("/imu/data")};
  const std::string plan = r.queryPlan(window);
  EXPECT_THAT(plan, HasSubstr("USING INDEX timestamp_idx (timestamp>? AND timestamp<?)"));
  EXPECT_THAT(plan, ::testing::Not(HasSubstr("TEMP B-TREE")));  // no sort: the index's order
  const auto s = test::stamps(r, window);
  ASSERT_EQ(s.size(), 20u);
  EXPECT_EQ(s.front().first, kT0 + 101000000);
}

TEST(Rosbag2Reader, ReadsADb3WithoutItsTimestampIndex) {
  const fs::path dir = scratch("no_index");
  fs::copy_file(fixture("imu_cloud.db3"), dir / "x.db3");
  sql(dir / "x.db3", "DROP INDEX timestamp_idx;");
  const auto r = openRecording((dir / "x.db3").string());
  ASSERT_EQ(r->warnings().size(), 1u);
  EXPECT_EQ(r->warnings()[0],
            "no index on the message timestamps: reading sorts the whole table first");
  EXPECT_EQ(test::describeAll(*r), test::describeAll(*openRecording(fixture("imu_cloud.db3"))));
}

// On a read-only medium: nothing is written beside the file (no journal, no lock file).
TEST(Rosbag2Reader, ReadsFromAReadOnlyFolderWithoutWritingThere) {
  const fs::path dir = scratch("read_only");
  fs::copy(fixture("imu_cloud_db3"), dir / "bag");
  fs::permissions(dir / "bag", fs::perms::owner_read | fs::perms::owner_exec);
  std::set<std::string> before;
  for (const auto& e : fs::directory_iterator(dir / "bag"))
    before.insert(e.path().filename().string());
  {
    const auto r = openRecording((dir / "bag").string());
    EXPECT_EQ(test::stamps(*r).size(), 84u);
    std::set<std::string> during;
    for (const auto& e : fs::directory_iterator(dir / "bag"))
      during.insert(e.path().filename().string());
    EXPECT_EQ(during, before);
  }
  fs::permissions(dir / "bag", fs::perms::owner_all);
}

TEST(Rosbag2Reader, WarnsOfAWriteAheadLogItCannotRead) {
  const fs::path dir = scratch("wal");
  fs::copy_file(fixture("imu_cloud.db3"), dir / "x.db3");
  writeText(dir / "x.db3-wal", "not empty");
  const auto r = openRecording((dir / "x.db3").string());
  ASSERT_EQ(r->warnings().size(), 1u);
  EXPECT_THAT(r->warnings()[0],
              HasSubstr("x.db3-wal (a write-ahead log left by a recorder that did not "
                        "close the file) is not read: its messages are missing"));
}

TEST(Rosbag2Reader, FolderErrorsNameWhatIsMissing) {
  const fs::path dir = scratch("folders");
  fs::copy(fixture("imu_cloud_db3"), dir / "no_metadata");
  fs::remove(dir / "no_metadata" / "metadata.yaml");
  const std::string no_metadata = (dir / "no_metadata").string();
  EXPECT_EQ(identifyRecording(no_metadata), RecordingKind::kPlainFolder);
  EXPECT_THAT(
      [&] { openRecording(no_metadata); },
      ::testing::ThrowsMessage<RecordingError>(
          no_metadata + ": a rosbag2 folder without metadata.yaml (open its files one by one: "
                        "imu_cloud_db3_0.db3, imu_cloud_db3_1.db3)"));
  EXPECT_THAT([&] { Rosbag2FolderReader r(no_metadata); },
              ::testing::ThrowsMessage<RecordingError>(no_metadata +
                                                       ": a rosbag2 folder without metadata.yaml"));
  fs::create_directories(dir / "empty");
  EXPECT_THAT([&] { openRecording((dir / "empty").string()); },
              ::testing::ThrowsMessage<RecordingError>(
                  HasSubstr("a folder without metadata.yaml or any .db3 "
                            "or .mcap file: not a rosbag2 recording")));

  fs::copy(fixture("imu_cloud_db3"), dir / "missing_file");
  fs::remove(dir / "missing_file" / "imu_cloud_db3_1.db3");
  const std::string missing = (dir / "missing_file").string();
  EXPECT_THAT([&] { openRecording(missing); },
              ::testing::ThrowsMessage<RecordingError>(
                  missing + ": a rosbag2 folder: metadata.yaml lists imu_cloud_db3_1.db3, which is "
                            "not in the folder"));

  // metadata.yaml itself names its folder.
  EXPECT_EQ(test::stamps(*openRecording(fixture("imu_cloud_db3/metadata.yaml"))).size(), 84u);
}

TEST(Rosbag2Reader, ReadsFoxyPathsAndRefusesCompressedRecordings) {
  const fs::path dir = scratch("metadata_variants");
  fs::copy(fixture("imu_cloud_db3"), dir / "bag");
  const std::string yaml = readText(dir / "bag" / "metadata.yaml");
  // Foxy (version 4) wrote the paths with the folder's name in front.
  std::string foxy = yaml;
  for (const char* f : {"    - imu_cloud_db3_0.db3", "    - imu_cloud_db3_1.db3"})
    foxy.replace(foxy.find(f), std::strlen(f), std::string("    - bag/") + (f + 6));
  writeText(dir / "bag" / "metadata.yaml", foxy);
  EXPECT_EQ(test::stamps(*openRecording((dir / "bag").string())).size(), 84u);

  std::string compressed = yaml;
  compressed.replace(compressed.find("compression_format: \"\""), 22, "compression_format: zstd");
  compressed.replace(compressed.find("compression_mode: \"\""), 20, "compression_mode: FILE");
  writeText(dir / "bag" / "metadata.yaml", compressed);
  EXPECT_THAT(
      [&] { openRecording((dir / "bag").string()); },
      ::testing::ThrowsMessage<RecordingError>(HasSubstr(
          "a rosbag2 folder: metadata.yaml: the recording is compressed (zstd, per file), which "
          "is not read: decompress it first")));

  writeText(dir / "bag" / "metadata.yaml",
            "rosbag2_bagfile_information:\n  version: 5\n\tstorage_identifier: x\n");
  EXPECT_THAT([&] { openRecording((dir / "bag").string()); },
              ::testing::ThrowsMessage<RecordingError>(
                  (dir / "bag").string() +
                  ": a rosbag2 folder: metadata.yaml line 3: a tab in the indentation"));
  writeText(dir / "bag" / "metadata.yaml", yaml.substr(0, yaml.find("  relative_file_paths")));
  EXPECT_THAT(
      [&] { openRecording((dir / "bag").string()); },
      ::testing::ThrowsMessage<RecordingError>(HasSubstr("metadata.yaml no relative_file_paths")));
  std::string other_storage = yaml;
  other_storage.replace(other_storage.find("sqlite3"), 7, "my_db");
  writeText(dir / "bag" / "metadata.yaml", other_storage);
  EXPECT_THAT([&] { openRecording((dir / "bag").string()); },
              ::testing::ThrowsMessage<RecordingError>(HasSubstr(
                  "metadata.yaml: storage 'my_db' is not supported (sqlite3 and mcap are)")));
}

TEST(Rosbag2Reader, SqliteErrorsNameTheFile) {
  const fs::path dir = scratch("sqlite_errors");
  sql(dir / "other.db3", "CREATE TABLE t(x INTEGER);");
  EXPECT_THAT(
      [&] { openRecording((dir / "other.db3").string()); },
      ::testing::ThrowsMessage<RecordingError>(
          (dir / "other.db3").string() +
          ": a rosbag2 SQLite file (.db3): an SQLite database without the rosbag2 tables 'topics' "
          "and 'messages'"));

  fs::copy_file(fixture("imu_cloud.db3"), dir / "orphan.db3");
  sql(dir / "orphan.db3",
      "INSERT INTO messages(topic_id, timestamp, data) VALUES (42, 1, x'00010000');");
  const auto orphan = openRecording((dir / "orphan.db3").string());
  EXPECT_THAT([&] { test::stamps(*orphan); },
              ::testing::ThrowsMessage<RecordingError>(
                  HasSubstr("orphan.db3: a rosbag2 SQLite file (.db3): a message of topic_id 42, "
                            "which the topics table lacks")));

  // Cut in half: an error naming the file, at opening or while reading; never a crash.
  const std::string bytes = test::fileBytes(fixture("imu_cloud.db3"));
  for (const std::size_t cut : {std::size_t{100}, bytes.size() / 2, bytes.size() - 4096}) {
    std::ofstream(dir / "cut.db3", std::ios::binary)
        .write(bytes.data(), static_cast<std::streamsize>(cut));
    try {
      const auto r = openRecording((dir / "cut.db3").string());
      test::describeAll(*r);
      ADD_FAILURE() << "a .db3 cut at " << cut << " read without an error";
    } catch (const RecordingError& e) {
      EXPECT_THAT(e.what(), HasSubstr("cut.db3: a rosbag2 SQLite file (.db3): ")) << cut;
    }
  }
}

TEST(OpenRecording, SaysWhatAPathIs) {
  const fs::path dir = scratch("front_door");
  writeText(dir / "old.bag", "#ROSBAG V2.0\nE\0\0\0");
  EXPECT_EQ(identifyRecording((dir / "old.bag").string()), RecordingKind::kRos1Bag);
  EXPECT_THAT(
      [&] { openRecording((dir / "old.bag").string()); },
      ::testing::ThrowsMessage<RecordingError>(
          (dir / "old.bag").string() +
          ": a ROS 1 bag (#ROSBAG V2.0), not a ROS 2 recording: it is read by the ROS 1 importer"));
  writeText(dir / "empty.mcap", "");
  EXPECT_THAT([&] { openRecording((dir / "empty.mcap").string()); },
              ::testing::ThrowsMessage<RecordingError>((dir / "empty.mcap").string() +
                                                       ": an empty file, not a recording"));
  EXPECT_THAT([&] { openRecording((dir / "nothing").string()); },
              ::testing::ThrowsMessage<RecordingError>((dir / "nothing").string() +
                                                       ": no such file or folder"));
  EXPECT_EQ(describe(identifyRecording(fixture("imu_cloud_mcap"))), "a rosbag2 folder");
  EXPECT_EQ(describe(identifyRecording(fixture("imu_cloud_zstd.mcap"))), "an MCAP file (ROS 2)");
}

TEST(BagMetadata, ReadsHumblesForm) {
  const BagMetadata m = parseBagMetadata(readText(fixture("imu_cloud_db3/metadata.yaml")));
  EXPECT_EQ(m.version, 5);
  EXPECT_EQ(m.storage_identifier, "sqlite3");
  EXPECT_EQ(m.relative_file_paths,
            (std::vector<std::string>{"imu_cloud_db3_0.db3", "imu_cloud_db3_1.db3"}));
  ASSERT_EQ(m.topics.size(), 3u);
  EXPECT_EQ(m.topics[1].name, "/aeva/AeriesII/point_cloud_frame");
  EXPECT_EQ(m.topics[1].type, kPointCloud2Type);
  EXPECT_EQ(m.topics[1].serialization_format, "cdr");
  EXPECT_EQ(m.topics[1].message_count, 3u);
  EXPECT_EQ(m.starting_time, kT0 + 500000);
  EXPECT_EQ(m.duration, 395500000);
  EXPECT_EQ(m.compression_format, "");
}

TEST(BagMetadata, ReadsTheLaterFormWithQosLists) {
  const BagMetadata m = parseBagMetadata(readText(fixture("imu_cloud_mcap/metadata.yaml")));
  EXPECT_EQ(m.version, 9);
  EXPECT_EQ(m.storage_identifier, "mcap");
  EXPECT_EQ(m.relative_file_paths,
            (std::vector<std::string>{"imu_cloud_mcap_0.mcap", "imu_cloud_mcap_1.mcap"}));
  ASSERT_EQ(m.topics.size(), 3u);
  EXPECT_EQ(m.topics[2].name, "/tf_static");
  EXPECT_EQ(m.topics[0].message_count, 80u);
}

TEST(BagMetadata, ReadsFlowListsQuotesCommentsAndBlockScalars) {
  const BagMetadata m = parseBagMetadata(
      "# written by hand\n"
      "rosbag2_bagfile_information:\n"
      "  version: 6   # a comment\n"
      "  storage_identifier: 'sqlite3'\n"
      "  relative_file_paths: [a_0.db3, \"b #1.db3\"]\n"
      "  custom_data: |\n"
      "    key: value\n"
      "    - not a list\n"
      "  topics_with_message_count:\n"
      "  - topic_metadata:\n"
      "      name: \"/a\"\n"
      "      type: std_msgs/msg/String\n"
      "      serialization_format: cdr\n"
      "      offered_qos_profiles: \"- history: 3\\n\n"
      "        \\  depth: 0\"\n"
      "    message_count: 2\n"
      "  compression_format: ~\n");
  EXPECT_EQ(m.version, 6);
  EXPECT_EQ(m.storage_identifier, "sqlite3");
  EXPECT_EQ(m.relative_file_paths, (std::vector<std::string>{"a_0.db3", "b #1.db3"}));
  ASSERT_EQ(m.topics.size(), 1u);
  EXPECT_EQ(m.topics[0].name, "/a");
  EXPECT_EQ(m.topics[0].message_count, 2u);
  EXPECT_FALSE(m.starting_time);
}

TEST(BagMetadata, SaysWhereItStopsUnderstanding) {
  EXPECT_THAT(
      [] { parseBagMetadata("version: 5\n"); },
      ::testing::ThrowsMessage<std::runtime_error>("no rosbag2_bagfile_information mapping"));
  EXPECT_THAT([] { parseBagMetadata("rosbag2_bagfile_information:\n  a: &x 1\n"); },
              ::testing::ThrowsMessage<std::runtime_error>(
                  "line 2: anchors, aliases and tags are not supported"));
  EXPECT_THAT([] { parseBagMetadata("rosbag2_bagfile_information:\n  a: 1\n    b: 2\n"); },
              ::testing::ThrowsMessage<std::runtime_error>("line 3: unexpected indentation"));
  EXPECT_THAT([] { parseBagMetadata("rosbag2_bagfile_information:\n  version: five\n"); },
              ::testing::ThrowsMessage<std::runtime_error>(
                  "line 2: version is not a whole number: 'five'"));
  EXPECT_THAT([] { parseBagMetadata("rosbag2_bagfile_information:\n  a: \"open\n"); },
              ::testing::ThrowsMessage<std::runtime_error>(
                  "line 2: a quoted value without its closing quote"));
  EXPECT_THAT([] { parseBagMetadata("rosbag2_bagfile_information:\n  a: 1\n  a: 2\n"); },
              ::testing::ThrowsMessage<std::runtime_error>("line 3: key 'a' given twice"));
}

}  // namespace
}  // namespace freeinit::ros2
