// Reads the messages of one rosbag2 SQLite file (.db3), the storage of rosbag2 up to Humble:
//   topics(id, name, type, serialization_format, offered_qos_profiles)
//   messages(id, topic_id, timestamp, data)   with an index on timestamp
// (later versions add tables such as schema, metadata and message_definitions, and columns:
// ignored). The file is opened read-only and immutable (no lock, no journal), so a recording on a
// read-only medium opens; a write-ahead log beside it (<file>-wal, left by a recorder that did
// not close the file) is then not read, with a warning.
//
// Messages come in timestamp order (ties by row id, the order of recording). A window [start,
// end] is a WHERE clause on the timestamp, answered through the timestamp index: reading a window
// costs the window. SQLite errors (a corrupt or truncated file) throw RecordingError
// "<path>: a rosbag2 SQLite file (.db3): <SQLite's message>".
#pragma once

#include <freeinit/ros2/recording.h>

#include <memory>
#include <string>

namespace freeinit::ros2 {

class SqliteBagReader final : public Recording {
 public:
  /// Opens `path`. Throws RecordingError (not an SQLite file, no rosbag2 tables, SQLite errors).
  explicit SqliteBagReader(const std::string& path);
  ~SqliteBagReader() override;

  void start(const ReadOptions& options) override;
  bool next(Message& message) override;

  /// SQLite's plan for reading `options` (EXPLAIN QUERY PLAN, one step per line): shows whether
  /// the timestamp index answers the window.
  std::string queryPlan(const ReadOptions& options) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace freeinit::ros2
