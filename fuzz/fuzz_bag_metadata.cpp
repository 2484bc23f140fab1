// Fuzz harness: the text of a rosbag2 metadata.yaml through its parser (ros2/bag_metadata.h and
// the YAML subset it reads), a hand-written parser of user input.
// Invariants: what parses holds no more files, topics or text than the input has bytes, and
// parsing is deterministic.
#include <freeinit/ros2/bag_metadata.h>

#include <stdexcept>

#include "harness.h"

namespace freeinit::fuzz {

std::string fuzzOne(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  ros2::BagMetadata m;
  try {
    m = ros2::parseBagMetadata(text);
  } catch (const std::runtime_error& e) {
    return "error: " + firstLine(e.what());
  }
  std::size_t chars = m.storage_identifier.size() + m.compression_format.size();
  for (const std::string& f : m.relative_file_paths) chars += f.size();
  for (const ros2::BagMetadata::Topic& t : m.topics) chars += t.name.size() + t.type.size();
  if (m.relative_file_paths.size() + m.topics.size() > size || chars > size)
    broken("more parsed than the input holds");
  const ros2::BagMetadata again = ros2::parseBagMetadata(text);
  if (again.relative_file_paths != m.relative_file_paths || again.topics.size() != m.topics.size())
    broken("parsing is not deterministic");
  return "ok: storage '" + m.storage_identifier + "', " +
         std::to_string(m.relative_file_paths.size()) + " file(s), " +
         std::to_string(m.topics.size()) + " topic(s)";
}

}  // namespace freeinit::fuzz
