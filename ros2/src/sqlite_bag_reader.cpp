#include <freeinit/ros2/sqlite_bag_reader.h>
#include <sqlite3.h>
#include <sys/stat.h>

#include <cctype>
#include <map>
#include <stdexcept>
#include <tuple>
#include <vector>

namespace freeinit::ros2 {
namespace {

struct CloseDb {
  void operator()(sqlite3* db) const { sqlite3_close(db); }
};
struct FinalizeStatement {
  void operator()(sqlite3_stmt* s) const { sqlite3_finalize(s); }
};
using Statement = std::unique_ptr<sqlite3_stmt, FinalizeStatement>;

// "file:" URI of a path: every byte but the unreserved ones and '/' percent-encoded.
std::string fileUri(const std::string& path) {
  std::string uri = "file:";
  const char* digits = "0123456789ABCDEF";
  for (const unsigned char c : path) {
    if (std::isalnum(c) || c == '/' || c == '-' || c == '_' || c == '.' || c == '~') {
      uri += static_cast<char>(c);
    } else {
      uri += '%';
      uri += digits[c >> 4];
      uri += digits[c & 15];
    }
  }
  return uri + "?immutable=1";
}

}  // namespace

struct SqliteBagReader::Impl {
  std::unique_ptr<sqlite3, CloseDb> db;
  std::map<std::int64_t, std::size_t> topic_of_id;  ///< topics.id -> topic index
  std::vector<std::vector<std::int64_t>> ids_of_topic;
  Statement query;

  Statement prepare(const std::string& sql) const {
    sqlite3_stmt* s = nullptr;
    if (sqlite3_prepare_v2(db.get(), sql.c_str(), -1, &s, nullptr) != SQLITE_OK)
      throw std::runtime_error(sqlite3_errmsg(db.get()));
    return Statement(s);
  }

  std::string messageQuery(const ReadOptions& o) const {
    std::string sql =
        "SELECT topic_id, timestamp, data FROM messages WHERE timestamp >= ?1 AND timestamp <= ?2";
    if (!o.topics.empty()) {
      std::string ids;
      for (const std::size_t t : o.topics)
        for (const std::int64_t id : ids_of_topic[t])
          ids += (ids.empty() ? "" : ",") + std::to_string(id);
      sql += " AND topic_id IN (" + ids + ")";
    }
    return sql + " ORDER BY timestamp, id";
  }

  Statement bind(const ReadOptions& o) const {
    Statement s = prepare(messageQuery(o));
    sqlite3_bind_int64(s.get(), 1, o.start);
    sqlite3_bind_int64(s.get(), 2, o.end);
    return s;
  }
};

SqliteBagReader::SqliteBagReader(const std::string& path)
    : Recording(path, "a rosbag2 SQLite file (.db3)"), impl_(std::make_unique<Impl>()) {
  try {
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode))
      throw std::runtime_error("no such file");
    sqlite3* db = nullptr;
    const int rc = sqlite3_open_v2(fileUri(path).c_str(), &db,
                                   SQLITE_OPEN_READONLY | SQLITE_OPEN_URI, nullptr);
    impl_->db.reset(db);
    if (rc != SQLITE_OK) throw std::runtime_error(db ? sqlite3_errmsg(db) : "cannot open");

    bool has_topics = false, has_messages = false, has_index = false;
    Statement tables = impl_->prepare("SELECT type, name, tbl_name, sql FROM sqlite_master");
    int rc_step;
    while ((rc_step = sqlite3_step(tables.get())) == SQLITE_ROW) {
      const auto text = [&](int col) {
        const unsigned char* v = sqlite3_column_text(tables.get(), col);
        return v ? std::string(reinterpret_cast<const char*>(v)) : std::string();
      };
      if (text(0) == "table" && text(1) == "topics") has_topics = true;
      if (text(0) == "table" && text(1) == "messages") has_messages = true;
      if (text(0) == "index" && text(2) == "messages" &&
          text(3).find("timestamp") != std::string::npos)
        has_index = true;
    }
    if (rc_step != SQLITE_DONE) throw std::runtime_error(sqlite3_errmsg(impl_->db.get()));
    if (!has_topics || !has_messages)
      throw std::runtime_error(
          "an SQLite database without the rosbag2 tables 'topics' and 'messages'");

    Statement topics =
        impl_->prepare("SELECT id, name, type, serialization_format FROM topics ORDER BY id");
    std::map<std::tuple<std::string, std::string, std::string>, std::size_t> by_name;
    while ((rc_step = sqlite3_step(topics.get())) == SQLITE_ROW) {
      const auto text = [&](int col) {
        const unsigned char* v = sqlite3_column_text(topics.get(), col);
        return v ? std::string(reinterpret_cast<const char*>(v)) : std::string();
      };
      const TopicInfo t{text(1), text(2), text(3), std::nullopt};
      const auto [it, added] =
          by_name.emplace(std::tuple(t.name, t.type, t.encoding), topics_.size());
      const std::size_t index = it->second;
      if (added) {
        topics_.push_back(t);
        impl_->ids_of_topic.emplace_back();
      }
      const std::int64_t id = sqlite3_column_int64(topics.get(), 0);
      impl_->topic_of_id[id] = index;
      impl_->ids_of_topic[index].push_back(id);
    }
    if (rc_step != SQLITE_DONE) throw std::runtime_error(sqlite3_errmsg(impl_->db.get()));

    if (has_index) {
      Statement range = impl_->prepare("SELECT MIN(timestamp), MAX(timestamp) FROM messages");
      if (sqlite3_step(range.get()) == SQLITE_ROW &&
          sqlite3_column_type(range.get(), 0) != SQLITE_NULL)
        time_range_ =
            TimeRange{sqlite3_column_int64(range.get(), 0), sqlite3_column_int64(range.get(), 1)};
    } else {
      warnings_.push_back(
          "no index on the message timestamps: reading sorts the whole table first");
    }
    struct stat wal {};
    if (::stat((path + "-wal").c_str(), &wal) == 0 && wal.st_size > 0)
      warnings_.push_back(path +
                          "-wal (a write-ahead log left by a recorder that did not close the "
                          "file) is not read: its messages are missing");
  } catch (const std::exception& e) {
    throw error(e.what());
  }
  start({});
}

SqliteBagReader::~SqliteBagReader() = default;

void SqliteBagReader::start(const ReadOptions& options) {
  checkOptions(options);
  try {
    impl_->query = impl_->bind(options);
  } catch (const std::exception& e) {
    throw error(e.what());
  }
}

bool SqliteBagReader::next(Message& message) {
  sqlite3_stmt* s = impl_->query.get();
  const int rc = sqlite3_step(s);
  if (rc == SQLITE_DONE) return false;
  if (rc != SQLITE_ROW) throw error(sqlite3_errmsg(impl_->db.get()));
  const std::int64_t id = sqlite3_column_int64(s, 0);
  const auto topic = impl_->topic_of_id.find(id);
  if (topic == impl_->topic_of_id.end())
    throw error("a message of topic_id " + std::to_string(id) + ", which the topics table lacks");
  message.topic = topic->second;
  message.log_time = sqlite3_column_int64(s, 1);
  const auto* data = static_cast<const std::uint8_t*>(sqlite3_column_blob(s, 2));
  const int n = sqlite3_column_bytes(s, 2);
  if (data == nullptr || n <= 0)
    message.data.clear();
  else
    message.data.assign(data, data + n);
  return true;
}

std::string SqliteBagReader::queryPlan(const ReadOptions& options) const {
  Statement s = impl_->prepare("EXPLAIN QUERY PLAN " + impl_->messageQuery(options));
  std::string plan;
  while (sqlite3_step(s.get()) == SQLITE_ROW) {
    const unsigned char* detail = sqlite3_column_text(s.get(), 3);
    plan += (detail ? reinterpret_cast<const char*>(detail) : "") + std::string("\n");
  }
  return plan;
}

}  // namespace freeinit::ros2
