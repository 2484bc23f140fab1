#include <freeinit/ros2/mcap_reader.h>
#include <freeinit/ros2/open_recording.h>
#include <freeinit/ros2/rosbag2_folder_reader.h>
#include <freeinit/ros2/sqlite_bag_reader.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace freeinit::ros2 {
namespace {

namespace fs = std::filesystem;

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

}  // namespace

Rosbag2FolderReader::Rosbag2FolderReader(const std::string& folder, const ReaderLimits& limits)
    : Recording(folder, "a rosbag2 folder") {
  const fs::path dir(folder);
  const fs::path yaml = dir / "metadata.yaml";
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw error("not a folder");
  if (!fs::is_regular_file(yaml, ec))
    throw RecordingError(folder + ": a rosbag2 folder without metadata.yaml");
  std::ifstream in(yaml, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  if (!in) throw error("cannot read metadata.yaml");
  try {
    metadata_ = parseBagMetadata(text.str());
  } catch (const std::exception& e) {
    throw error(std::string("metadata.yaml ") + e.what());
  }
  const std::string storage = metadata_.storage_identifier;
  if (!storage.empty() && storage != "sqlite3" && storage != "mcap")
    throw error("metadata.yaml: storage '" + storage + "' is not supported (sqlite3 and mcap are)");
  if (!metadata_.compression_format.empty())
    throw error("metadata.yaml: the recording is compressed (" + metadata_.compression_format +
                ", per " +
                (metadata_.compression_mode.empty() ? "?" : lower(metadata_.compression_mode)) +
                "), which is not read: decompress it first (ros2 bag convert, or zstd -d each file "
                "and list the decompressed files)");
  if (metadata_.relative_file_paths.empty()) throw error("metadata.yaml lists no file");

  for (const std::string& relative : metadata_.relative_file_paths) {
    // Foxy's metadata (version 4) gives the paths with the folder's name in front.
    fs::path file = dir / relative;
    if (!fs::exists(file, ec) && fs::exists(dir / fs::path(relative).filename(), ec))
      file = dir / fs::path(relative).filename();
    if (!fs::is_regular_file(file, ec))
      throw error("metadata.yaml lists " + relative + ", which is not in the folder");
    const RecordingKind kind = identifyRecording(file.string());
    if (kind == RecordingKind::kMcap)
      files_.push_back(std::make_unique<McapReader>(file.string(), limits));
    else if (kind == RecordingKind::kSqlite)
      files_.push_back(std::make_unique<SqliteBagReader>(file.string()));
    else
      throw error("metadata.yaml lists " + relative + ", which is " + describe(kind) +
                  ", not an MCAP or SQLite file");
  }

  // Our topics: the union of the files', matched by name, type and encoding.
  for (const auto& f : files_) {
    std::vector<std::size_t> map;
    for (const TopicInfo& t : f->topics()) {
      std::size_t index = topics_.size();
      for (std::size_t k = 0; k < topics_.size(); ++k)
        if (topics_[k].name == t.name && topics_[k].type == t.type &&
            topics_[k].encoding == t.encoding)
          index = k;
      if (index == topics_.size()) topics_.push_back({t.name, t.type, t.encoding, std::nullopt});
      map.push_back(index);
    }
    topic_map_.push_back(map);
    for (const std::string& w : f->warnings())
      warnings_.push_back(fs::path(f->path()).filename().string() + ": " + w);
    ordered_ = ordered_ && f->ordered();
  }
  for (TopicInfo& t : topics_)
    for (const BagMetadata::Topic& m : metadata_.topics)
      if (m.name == t.name && m.type == t.type) t.message_count = m.message_count;
  if (metadata_.starting_time && metadata_.duration) {
    time_range_ =
        TimeRange{*metadata_.starting_time, *metadata_.starting_time + *metadata_.duration};
  } else {
    for (const auto& f : files_) {
      if (!f->timeRange()) continue;
      if (!time_range_) time_range_ = f->timeRange();
      time_range_->first = std::min(time_range_->first, f->timeRange()->first);
      time_range_->last = std::max(time_range_->last, f->timeRange()->last);
    }
  }
  start({});
}

Rosbag2FolderReader::~Rosbag2FolderReader() = default;

void Rosbag2FolderReader::start(const ReadOptions& options) {
  checkOptions(options);
  heads_.assign(files_.size(), std::nullopt);
  for (std::size_t f = 0; f < files_.size(); ++f) {
    ReadOptions own{options.start, options.end, {}};
    for (std::size_t t = 0; t < topic_map_[f].size(); ++t)
      if (std::find(options.topics.begin(), options.topics.end(), topic_map_[f][t]) !=
          options.topics.end())
        own.topics.push_back(t);
    if (!options.topics.empty() && own.topics.empty()) continue;  // none of the topics in this file
    files_[f]->start(own);
    Message m;
    if (files_[f]->next(m)) heads_[f] = std::move(m);
  }
}

bool Rosbag2FolderReader::next(Message& message) {
  std::size_t best = heads_.size();
  for (std::size_t f = 0; f < heads_.size(); ++f)
    if (heads_[f] && (best == heads_.size() || heads_[f]->log_time < heads_[best]->log_time))
      best = f;
  if (best == heads_.size()) return false;
  message = std::move(*heads_[best]);
  message.topic = topic_map_[best][message.topic];
  Message m;
  if (files_[best]->next(m))
    heads_[best] = std::move(m);
  else
    heads_[best].reset();
  return true;
}

}  // namespace freeinit::ros2
