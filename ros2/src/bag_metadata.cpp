#include <freeinit/ros2/bag_metadata.h>

#include <cerrno>
#include <cstdlib>
#include <stdexcept>

#include "yaml_subset.h"

namespace freeinit::ros2 {
namespace {

std::string where(const YamlNode& n) { return "line " + std::to_string(n.line) + ": "; }

std::string text(const YamlNode* n, const std::string& key) {
  if (n == nullptr || n->kind == YamlNode::Kind::kNull) return {};
  if (n->kind != YamlNode::Kind::kScalar)
    throw std::runtime_error(where(*n) + key + " is not a value");
  return n->scalar;
}

std::int64_t integer(const YamlNode* n, const std::string& key) {
  const std::string s = text(n, key);
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(s.c_str(), &end, 10);
  if (s.empty() || *end != '\0' || errno == ERANGE)
    throw std::runtime_error((n ? where(*n) : std::string()) + key + " is not a whole number: '" +
                             s + "'");
  return v;
}

const YamlNode* child(const YamlNode* n, const char* key) { return n ? n->get(key) : nullptr; }

}  // namespace

BagMetadata parseBagMetadata(const std::string& yaml) {
  const YamlNode root = parseYamlSubset(yaml);
  const YamlNode* info = root.get("rosbag2_bagfile_information");
  if (info == nullptr || info->kind != YamlNode::Kind::kMap)
    throw std::runtime_error("no rosbag2_bagfile_information mapping");
  BagMetadata m;
  if (const YamlNode* v = info->get("version")) m.version = static_cast<int>(integer(v, "version"));
  m.storage_identifier = text(info->get("storage_identifier"), "storage_identifier");
  const YamlNode* files = info->get("relative_file_paths");
  if (files == nullptr) throw std::runtime_error("no relative_file_paths");
  if (files->kind == YamlNode::Kind::kList) {
    for (const YamlNode& f : files->items)
      m.relative_file_paths.push_back(text(&f, "relative_file_paths"));
  } else if (files->kind != YamlNode::Kind::kNull) {
    throw std::runtime_error(where(*files) + "relative_file_paths is not a list");
  }
  if (const YamlNode* topics = info->get("topics_with_message_count");
      topics != nullptr && topics->kind == YamlNode::Kind::kList) {
    for (const YamlNode& t : topics->items) {
      const YamlNode* meta = t.get("topic_metadata");
      if (meta == nullptr) throw std::runtime_error(where(t) + "a topic without topic_metadata");
      BagMetadata::Topic topic;
      topic.name = text(meta->get("name"), "name");
      topic.type = text(meta->get("type"), "type");
      topic.serialization_format = text(meta->get("serialization_format"), "serialization_format");
      if (const YamlNode* c = t.get("message_count")) {
        const std::int64_t n = integer(c, "message_count");
        if (n < 0) throw std::runtime_error(where(*c) + "a negative message_count");
        topic.message_count = static_cast<std::uint64_t>(n);
      }
      m.topics.push_back(topic);
    }
  }
  if (const YamlNode* t = child(info->get("starting_time"), "nanoseconds_since_epoch"))
    m.starting_time = integer(t, "starting_time.nanoseconds_since_epoch");
  if (const YamlNode* d = child(info->get("duration"), "nanoseconds"))
    m.duration = integer(d, "duration.nanoseconds");
  m.compression_format = text(info->get("compression_format"), "compression_format");
  m.compression_mode = text(info->get("compression_mode"), "compression_mode");
  return m;
}

}  // namespace freeinit::ros2
