#include "yaml_subset.h"

#include <stdexcept>

namespace freeinit::ros2 {
namespace {

struct Line {
  int indent = 0;    ///< [columns]
  std::string text;  ///< after the indentation
  int number = 0;    ///< 1-based
};

bool isDash(const std::string& t) { return t == "-" || t.rfind("- ", 0) == 0; }

std::string trim(const std::string& s) {
  const std::size_t b = s.find_first_not_of(' ');
  if (b == std::string::npos) return {};
  return s.substr(b, s.find_last_not_of(' ') - b + 1);
}

class Parser {
 public:
  explicit Parser(const std::string& text) {
    int number = 0;
    std::size_t from = 0;
    while (from <= text.size()) {
      std::size_t to = text.find('\n', from);
      if (to == std::string::npos) to = text.size();
      std::string s = text.substr(from, to - from);
      from = to + 1;
      ++number;
      if (!s.empty() && s.back() == '\r') s.pop_back();
      const std::size_t indent = s.find_first_not_of(' ');
      if (indent == std::string::npos) continue;
      if (s[indent] == '\t') fail(number, "a tab in the indentation");
      const std::string rest = s.substr(indent);
      if (rest[0] == '#' || rest == "---" || rest == "...") continue;
      lines_.push_back({static_cast<int>(indent), trim(rest), number});
    }
  }

  YamlNode document() {
    if (lines_.empty()) return {};
    YamlNode root = node(lines_[0].indent);
    if (pos_ < lines_.size()) fail(lines_[pos_].number, "unexpected indentation");
    return root;
  }

 private:
  [[noreturn]] static void fail(int line, const std::string& what) {
    throw std::runtime_error("line " + std::to_string(line) + ": " + what);
  }

  YamlNode node(int indent) { return isDash(lines_[pos_].text) ? list(indent) : map(indent); }

  YamlNode list(int indent) {
    YamlNode n;
    n.kind = YamlNode::Kind::kList;
    n.line = lines_[pos_].number;
    while (pos_ < lines_.size() && lines_[pos_].indent == indent && isDash(lines_[pos_].text)) {
      Line& l = lines_[pos_];
      const std::size_t offset = l.text.find_first_not_of(' ', 1);
      if (offset == std::string::npos) {  // "-" alone: the item is on the next lines
        ++pos_;
        n.items.push_back(pos_ < lines_.size() && lines_[pos_].indent > indent
                              ? node(lines_[pos_].indent)
                              : YamlNode{YamlNode::Kind::kNull, {}, {}, {}, l.number});
        continue;
      }
      // "- item": the item starts at its own column, as if it were on a line of its own.
      l.indent += static_cast<int>(offset);
      l.text = l.text.substr(offset);
      if (isDash(l.text) || keyEnd(l.text) != std::string::npos) {
        n.items.push_back(node(l.indent));
      } else {
        ++pos_;
        n.items.push_back(inlineValue(l.text, l.number, indent));
      }
    }
    if (pos_ < lines_.size() && lines_[pos_].indent > indent)
      fail(lines_[pos_].number, "unexpected indentation");
    return n;
  }

  // Where the key of "key: value" (or "key:") ends, or npos when the line is not a key.
  static std::size_t keyEnd(const std::string& t) {
    if (t.empty() || t[0] == '"' || t[0] == '\'') {
      if (t.empty()) return std::string::npos;
      const std::size_t close = t.find(t[0], 1);
      if (close == std::string::npos || close + 1 >= t.size() || t[close + 1] != ':')
        return std::string::npos;
      return (close + 2 == t.size() || t[close + 2] == ' ') ? close + 1 : std::string::npos;
    }
    for (std::size_t i = 0; i < t.size(); ++i) {
      if (t[i] == '#' && i > 0 && t[i - 1] == ' ') return std::string::npos;
      if (t[i] == ':' && (i + 1 == t.size() || t[i + 1] == ' ')) return i;
    }
    return std::string::npos;
  }

  YamlNode map(int indent) {
    YamlNode n;
    n.kind = YamlNode::Kind::kMap;
    n.line = lines_[pos_].number;
    while (pos_ < lines_.size() && lines_[pos_].indent == indent) {
      const Line l = lines_[pos_];
      if (isDash(l.text)) fail(l.number, "a list item where a 'key: value' line was expected");
      const std::size_t end = keyEnd(l.text);
      if (end == std::string::npos) fail(l.number, "expected 'key: value', found '" + l.text + "'");
      std::string key = l.text.substr(0, end);
      if (key.size() >= 2 && (key[0] == '"' || key[0] == '\'')) key = key.substr(1, key.size() - 2);
      for (const auto& e : n.entries)
        if (e.first == key) fail(l.number, "key '" + key + "' given twice");
      const std::string value = trim(l.text.substr(end + 1));
      ++pos_;
      YamlNode child{YamlNode::Kind::kNull, {}, {}, {}, l.number};
      if (!value.empty() && value[0] != '#') {
        child = inlineValue(value, l.number, indent);
      } else if (pos_ < lines_.size() && lines_[pos_].indent > indent) {
        child = node(lines_[pos_].indent);
      } else if (pos_ < lines_.size() && lines_[pos_].indent == indent &&
                 isDash(lines_[pos_].text)) {
        child = list(indent);  // a sequence may sit at its key's indentation
      }
      n.entries.emplace_back(std::move(key), std::move(child));
    }
    if (pos_ < lines_.size() && lines_[pos_].indent > indent)
      fail(lines_[pos_].number, "unexpected indentation");
    return n;
  }

  // A value on the line of its key or dash; quoted scalars and block scalars may take the next
  // lines (those indented more than `parent`).
  YamlNode inlineValue(std::string v, int line, int parent) {
    YamlNode n{YamlNode::Kind::kScalar, {}, {}, {}, line};
    const char c = v[0];
    if (c == '"' || c == '\'') {
      // Continuation lines of a quoted scalar join with a space.
      while (!closedQuote(v) && pos_ < lines_.size() && lines_[pos_].indent > parent)
        v += " " + lines_[pos_++].text;
      std::size_t i = 1;
      for (; i < v.size(); ++i) {
        if (c == '\'' && v[i] == '\'') {
          if (i + 1 < v.size() && v[i + 1] == '\'') {
            n.scalar += '\'';
            ++i;
            continue;
          }
          break;
        }
        if (c == '"' && v[i] == '"') break;
        if (c == '"' && v[i] == '\\' && i + 1 < v.size()) {
          const char e = v[++i];
          n.scalar += e == 'n' ? '\n' : e == 't' ? '\t' : e == '0' ? '\0' : e;
          continue;
        }
        n.scalar += v[i];
      }
      if (i >= v.size()) fail(line, "a quoted value without its closing quote");
      const std::string rest = trim(v.substr(i + 1));
      if (!rest.empty() && rest[0] != '#') fail(line, "text after a quoted value: '" + rest + "'");
      return n;
    }
    if (c == '|' || c == '>') {
      while (pos_ < lines_.size() && lines_[pos_].indent > parent) {
        n.scalar += (n.scalar.empty() ? "" : (c == '|' ? "\n" : " ")) + lines_[pos_].text;
        ++pos_;
      }
      return n;
    }
    if (c == '&' || c == '*' || c == '!') fail(line, "anchors, aliases and tags are not supported");
    v = trim(v.substr(0, outsideQuotes(v, " #")));
    if (c == '{') {
      if (v != "{}") fail(line, "flow mappings other than {} are not supported");
      n.kind = YamlNode::Kind::kMap;
      return n;
    }
    if (c == '[') {
      if (v.back() != ']') fail(line, "a flow sequence not closed on its line");
      n.kind = YamlNode::Kind::kList;
      const std::string inner = trim(v.substr(1, v.size() - 2));
      std::size_t from = 0;
      while (!inner.empty() && from <= inner.size()) {
        const std::size_t to = from + outsideQuotes(inner.substr(from), ",");
        const std::string item = trim(inner.substr(from, to - from));
        if (item.empty() || item[0] == '[' || item[0] == '{')
          fail(line, "an unsupported flow sequence");
        n.items.push_back(inlineValue(item, line, parent));
        from = to + 1;
      }
      return n;
    }
    if (v == "~" || v == "null" || v == "Null" || v == "NULL") {
      n.kind = YamlNode::Kind::kNull;
      return n;
    }
    n.scalar = v;
    return n;
  }

  // Where `token` first occurs outside quoted text in `v` (v.size() when it does not). A quote
  // opens quoted text only where a scalar starts: at the beginning or after '[' or ','.
  static std::size_t outsideQuotes(const std::string& v, const std::string& token) {
    char quote = 0;
    char before = '[';  // the last character outside quotes that is not a space
    for (std::size_t i = 0; i < v.size(); ++i) {
      if (quote == 0) {
        if (v.compare(i, token.size(), token) == 0) return i;
        if ((v[i] == '"' || v[i] == '\'') && (before == '[' || before == ',')) {
          quote = v[i];
        } else if (v[i] != ' ') {
          before = v[i];
        }
      } else if (quote == '"' && v[i] == '\\') {
        ++i;
      } else if (v[i] == quote) {
        quote = 0;
        before = v[i];
      }
    }
    return v.size();
  }

  static bool closedQuote(const std::string& v) {
    for (std::size_t i = 1; i < v.size(); ++i) {
      if (v[0] == '"' && v[i] == '\\') {
        ++i;
        continue;
      }
      if (v[i] == v[0]) {
        if (v[0] == '\'' && i + 1 < v.size() && v[i + 1] == '\'') {
          ++i;
          continue;
        }
        return true;
      }
    }
    return false;
  }

  std::vector<Line> lines_;
  std::size_t pos_ = 0;
};

}  // namespace

const YamlNode* YamlNode::get(const std::string& key) const {
  if (kind != Kind::kMap) return nullptr;
  for (const auto& e : entries)
    if (e.first == key) return &e.second;
  return nullptr;
}

YamlNode parseYamlSubset(const std::string& text) { return Parser(text).document(); }

}  // namespace freeinit::ros2
