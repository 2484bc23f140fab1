#include <freeinit/ros2/recording.h>

namespace freeinit::ros2 {

std::string Recording::topicList() const {
  std::string list;
  for (const TopicInfo& t : topics_)
    list +=
        (list.empty() ? "" : ", ") + t.name + " (" + (t.type.empty() ? "no type" : t.type) + ")";
  return list.empty() ? std::string("no topic") : list;
}

std::size_t Recording::topic(const std::string& name, const std::string& expected_type) const {
  std::size_t found = topics_.size();
  for (std::size_t i = 0; i < topics_.size(); ++i) {
    if (topics_[i].name != name) continue;
    // A topic recorded with two types: take the expected one.
    if (found == topics_.size() || topics_[i].type == expected_type) found = i;
  }
  if (found == topics_.size())
    throw RecordingError(path_ + ": topic " + name +
                         " not found; the recording has: " + topicList());
  const TopicInfo& t = topics_[found];
  if (!expected_type.empty() && t.type != expected_type)
    throw RecordingError(path_ + ": topic " + name + " has type " +
                         (t.type.empty() ? std::string("(none given)") : t.type) + ", expected " +
                         expected_type);
  if (t.encoding != "cdr")
    throw RecordingError(path_ + ": topic " + name + " is encoded as '" + t.encoding +
                         "'; only 'cdr' (ROS 2) is read");
  return found;
}

RecordingError Recording::error(const std::string& what) const {
  return RecordingError(path_ + ": " + kind_ + ": " + what);
}

void Recording::checkOptions(const ReadOptions& options) const {
  for (const std::size_t t : options.topics)
    if (t >= topics_.size())
      throw RecordingError(path_ + ": topic index " + std::to_string(t) + " out of range (" +
                           std::to_string(topics_.size()) + " topics)");
}

}  // namespace freeinit::ros2
