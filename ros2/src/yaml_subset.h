// A parser for the block-style YAML that rosbag2 writes in metadata.yaml: nested mappings and
// sequences by indentation, "- key: value" items, plain, single- and double-quoted scalars (a
// double-quoted scalar may continue on the next lines), `~`/null, empty flow collections `[]`
// `{}`, flow sequences of scalars `[a, b]`, block scalars `|` `>`, and comments. Anchors, aliases,
// tags and other flow collections are refused with the line they are on. Not a YAML library:
// enough to read the keys a rosbag2 folder needs without one.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace freeinit::ros2 {

struct YamlNode {
  enum class Kind { kNull, kScalar, kMap, kList };
  Kind kind = Kind::kNull;
  std::string scalar;                                     ///< kScalar
  std::vector<std::pair<std::string, YamlNode>> entries;  ///< kMap, in file order
  std::vector<YamlNode> items;                            ///< kList
  int line = 0;                                           ///< 1-based line it starts on

  /// The value of `key` in a mapping; nullptr when absent or when this is not a mapping.
  const YamlNode* get(const std::string& key) const;
};

/// Parses `text`. Throws std::runtime_error "line N: <what is wrong>".
YamlNode parseYamlSubset(const std::string& text);

}  // namespace freeinit::ros2
