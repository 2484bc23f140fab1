#include <freeinit/io/ini_file.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <system_error>

namespace freeinit::config {
namespace {

std::string_view trim(std::string_view s) {
  const auto blank = [](char c) { return c == ' ' || c == '\t' || c == '\r'; };
  while (!s.empty() && blank(s.front())) s.remove_prefix(1);
  while (!s.empty() && blank(s.back())) s.remove_suffix(1);
  return s;
}

char lowerChar(char c) { return static_cast<char>(std::tolower(static_cast<unsigned char>(c))); }

bool validKeyName(std::string_view k) {
  return !k.empty() && std::all_of(k.begin(), k.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.' || c == '-';
  });
}

// Edits (insertion, deletion, substitution, swap of neighbours) between two names, ignoring case.
std::size_t editDistance(std::string_view a, std::string_view b) {
  const std::size_t n = a.size(), m = b.size();
  std::vector<std::vector<std::size_t>> d(n + 1, std::vector<std::size_t>(m + 1));
  for (std::size_t i = 0; i <= n; ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= m; ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= n; ++i) {
    for (std::size_t j = 1; j <= m; ++j) {
      const bool same = lowerChar(a[i - 1]) == lowerChar(b[j - 1]);
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + (same ? 0 : 1)});
      if (i > 1 && j > 1 && lowerChar(a[i - 1]) == lowerChar(b[j - 2]) &&
          lowerChar(a[i - 2]) == lowerChar(b[j - 1]))
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  }
  return d[n][m];
}

// "[section] key: " (or "[section]: " without a key): where in the file's structure an error is.
std::string prefix(const std::string& section, const std::string& key) {
  if (section.empty()) return key.empty() ? "" : key + ": ";
  return "[" + section + "]" + (key.empty() ? ": " : " " + key + ": ");
}

}  // namespace

bool sameName(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return lowerChar(x) == lowerChar(y);
         });
}

std::string closestName(std::string_view name, const std::vector<std::string>& candidates) {
  std::string best;
  std::size_t best_d = std::max<std::size_t>(1, std::min<std::size_t>(3, name.size() / 3)) + 1;
  for (const auto& c : candidates) {
    const std::size_t d = editDistance(name, c);
    if (d < best_d) {
      best_d = d;
      best = c;
    }
  }
  return best;
}

std::string quote(std::string_view text) {
  constexpr std::size_t kMax = 48;
  if (text.size() <= kMax) return "'" + std::string(text) + "'";
  return "'" + std::string(text.substr(0, kMax)) + "...'";
}

std::string cleanValue(std::string_view raw, std::string& value) {
  if (const auto c = raw.find_first_of(";#"); c != std::string_view::npos) raw = raw.substr(0, c);
  raw = trim(raw);
  if (raw.size() >= 2 && raw.front() == '"' && raw.back() == '"')
    raw = raw.substr(1, raw.size() - 2);
  value = std::string(raw);
  for (const char* expansion : {"${", "$env{", "$eval{"})
    if (value.find(expansion) != std::string::npos)
      return quote(value) +
             ": variables and expressions ($...{...}) are not expanded: write the value itself";
  return "";
}

const IniEntry* IniSection::find(std::string_view key) const {
  for (const auto& e : entries)
    if (sameName(e.key, key)) return &e;
  return nullptr;
}

const IniSection* IniFile::section(std::string_view name) const {
  for (const auto& s : sections_)
    if (sameName(s.name, name)) return &s;
  return nullptr;
}

std::string IniFile::where(int line) const {
  return line > 0 ? source_ + ":" + std::to_string(line) : source_;
}

void IniFile::fail(const std::string& section, const std::string& key,
                   const std::string& what) const {
  int line = 0;
  std::string in = prefix(section, key);
  if (const IniSection* s = this->section(section)) {
    line = s->line;
    if (const IniEntry* e = key.empty() ? nullptr : s->find(key)) {
      line = e->line;
      if (!e->given_as.empty())
        in = "[" + section + "] " + key + " (given as " + e->given_as + "): ";
    }
  }
  throw ConfigError(where(line) + ": " + in + what);
}

IniFile IniFile::withRenames(const std::vector<KeyRename>& renames,
                             const std::vector<std::string>& retired,
                             std::vector<std::string>& notices) const {
  const auto isRetired = [&](const std::string& name) {
    return std::any_of(retired.begin(), retired.end(),
                       [&](const std::string& r) { return sameName(r, name); });
  };
  const auto renameOf = [&](const IniSection& s, const IniEntry& e) -> const KeyRename* {
    for (const KeyRename& r : renames)
      if (sameName(r.from_section, s.name) && sameName(r.from_key, e.key)) return &r;
    return nullptr;
  };
  // The sections that stay, without the keys that move.
  IniFile out(source_);
  for (const IniSection& s : sections_) {
    if (s.checked && isRetired(s.name)) continue;
    IniSection kept = s;
    if (s.checked)
      kept.entries.erase(std::remove_if(kept.entries.begin(), kept.entries.end(),
                                        [&](const IniEntry& e) { return renameOf(s, e); }),
                         kept.entries.end());
    out.sections_.push_back(std::move(kept));
  }
  // The keys that move, in the order of the file.
  for (const IniSection& s : sections_) {
    if (!s.checked) continue;
    for (const IniEntry& e : s.entries) {
      const std::string given = "[" + s.name + "] " + e.key;
      const KeyRename* r = renameOf(s, e);
      if (!r) {
        if (!isRetired(s.name)) continue;
        std::vector<std::string> known;
        for (const KeyRename& k : renames)
          if (sameName(k.from_section, s.name)) known.push_back(k.from_key);
        const std::string near = closestName(e.key, known);
        throw ConfigError(where(e.line) + ": " + given + ": unknown key" +
                          (near.empty() ? "" : " (did you mean " + near + "?)"));
      }
      const std::string now = "[" + r->to_section + "] " + r->to_key;
      IniSection* target = nullptr;
      for (IniSection& t : out.sections_)
        if (sameName(t.name, r->to_section)) target = &t;
      if (!target) {
        IniSection created;
        created.name = r->to_section;
        out.sections_.push_back(std::move(created));
        target = &out.sections_.back();
      }
      if (const IniEntry* other = target->find(r->to_key))
        throw ConfigError(where(e.line) + ": " + given + ": is now " + now + ", also given" +
                          (other->given_as.empty() ? "" : " as " + other->given_as) + " (line " +
                          std::to_string(other->line) + "): give it once");
      IniEntry moved = e;
      moved.key = r->to_key;
      moved.given_as = given;
      target->entries.push_back(std::move(moved));
      notices.push_back(where(e.line) + ": " + given + " is now " + now +
                        " (the old name is read for now)");
    }
  }
  return out;
}

IniFile IniFile::parse(std::string_view text, std::string source, const ParseOptions& options) {
  IniFile ini(std::move(source));
  if (text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);  // UTF-8 byte order mark
  IniSection* current = nullptr;
  bool skipping = false;  // inside a section of another program
  int line_no = 0;
  auto fail = [&](const std::string& where_in, const std::string& what) {
    throw ConfigError(ini.where(line_no) + ": " + where_in + what);
  };
  while (!text.empty()) {
    ++line_no;
    const std::size_t nl = text.find('\n');
    std::string_view line = text.substr(0, nl);
    text.remove_prefix(nl == std::string_view::npos ? text.size() : nl + 1);
    for (const char c : line) {
      const auto u = static_cast<unsigned char>(c);
      if ((u < 0x20 && c != '\t' && c != '\r') || u == 0x7f) {
        std::ostringstream os;
        os << "binary data (byte 0x" << std::hex << static_cast<int>(u)
           << "): not an INI text file";
        fail("", os.str());
      }
    }
    line = trim(line);
    if (line.empty() || line.front() == ';' || line.front() == '#') continue;
    if (line.front() == '[') {
      const std::size_t close = line.find(']');
      if (close == std::string_view::npos) fail("", "malformed section header (no ']')");
      const std::string name(trim(line.substr(1, close - 1)));
      if (name.empty()) fail("", "empty section name '[]'");
      const std::string_view rest = trim(line.substr(close + 1));
      if (!rest.empty() && rest.front() != ';' && rest.front() != '#')
        fail("[" + name + "]: ", "unexpected text after the section header");
      if (const IniSection* earlier = ini.section(name))
        fail("[" + name + "]: ",
             "section given twice (first at line " + std::to_string(earlier->line) + ")");
      IniSection s;
      s.name = name;
      s.line = line_no;
      const auto& only = options.only_sections;
      s.checked = only.empty() || std::any_of(only.begin(), only.end(),
                                              [&](const auto& o) { return sameName(o, name); });
      skipping = !s.checked;
      ini.sections_.push_back(std::move(s));
      current = &ini.sections_.back();
      continue;
    }
    if (skipping || (!current && !options.only_sections.empty())) continue;
    const std::string where_in = current ? "[" + current->name + "] " : "";
    if (line.front() == '@')
      fail(where_in.empty() ? "" : where_in.substr(0, where_in.size() - 1) + ": ",
           quote(line) + ": directives such as @include and @define are not supported");
    const std::size_t eq = line.find('=');
    if (eq == std::string_view::npos)
      fail(where_in.empty() ? "" : where_in.substr(0, where_in.size() - 1) + ": ",
           quote(line) + ": expected 'key = value', a [section] or a comment");
    const std::string key(trim(line.substr(0, eq)));
    if (!validKeyName(key))
      fail(where_in, quote(key) + " is not a key name (letters, digits, '_', '.', '-')");
    if (!current) fail("", key + ": key outside a [section]");
    std::string value;
    if (const std::string err = cleanValue(line.substr(eq + 1), value); !err.empty())
      fail(where_in + key + ": ", err);
    if (const IniEntry* earlier = current->find(key))
      fail(where_in + key + ": ",
           "key given twice (first at line " + std::to_string(earlier->line) + ")");
    current->entries.push_back({key, std::move(value), line_no, ""});
  }
  return ini;
}

IniFile IniFile::load(const std::string& path, const ParseOptions& options) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (!std::filesystem::exists(status)) throw ConfigError(path + ": configuration file not found");
  if (std::filesystem::is_directory(status))
    throw ConfigError(path + ": is a directory, not a configuration file");
  if (!std::filesystem::is_regular_file(status)) throw ConfigError(path + ": not a regular file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ConfigError(path + ": cannot read: " + std::strerror(errno));
  // At most one byte more than accepted: enough to tell a binary file (e.g. a rawlog given as
  // the INI) from a text one, and a too large file from an accepted one.
  std::string text(kMaxBytes + 1, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  if (in.bad()) throw ConfigError(path + ": cannot read: " + std::strerror(errno));
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (text.size() > kMaxBytes) {
    const std::size_t bad =
        text.find_first_of(std::string("\0\x01\x02\x03\x04\x05\x06\x07\x08"
                                       "\x0b\x0c\x0e\x0f\x10\x11\x12\x13"
                                       "\x14\x15\x16\x17\x18\x19\x1a\x1b"
                                       "\x1c\x1d\x1e\x1f\x7f",
                                       30));
    if (bad != std::string::npos) {
      text.resize(text.find('\n', bad) == std::string::npos ? text.size() : text.find('\n', bad));
      return parse(text, path, options);  // reports the binary data on its line
    }
    throw ConfigError(path + ": too large for a configuration file (more than " +
                      std::to_string(kMaxBytes) + " bytes)");
  }
  return parse(text, path, options);
}

void IniFile::add(IniSection section) {
  if (this->section(section.name)) fail(section.name, "", "section given twice");
  IniSection clean;
  clean.name = section.name;
  clean.line = section.line;
  for (auto& e : section.entries) {
    if (!validKeyName(e.key))
      throw ConfigError(where(e.line) + ": [" + section.name + "] " + quote(e.key) +
                        " is not a key name");
    std::string value;
    if (const std::string err = cleanValue(e.value, value); !err.empty())
      throw ConfigError(where(e.line) + ": [" + section.name + "] " + e.key + ": " + err);
    if (clean.find(e.key))
      throw ConfigError(where(e.line) + ": [" + section.name + "] " + e.key + ": key given twice");
    clean.entries.push_back({e.key, std::move(value), e.line, ""});
  }
  sections_.push_back(std::move(clean));
}

void IniFile::requireKnownSections(const std::vector<std::string>& known,
                                   const std::vector<std::string>& former) const {
  const auto in = [](const std::vector<std::string>& names, const std::string& name) {
    return std::any_of(names.begin(), names.end(),
                       [&](const auto& k) { return sameName(k, name); });
  };
  for (const auto& s : sections_) {
    if (in(known, s.name) || in(former, s.name)) continue;
    std::string list;
    for (const auto& k : known) list += (list.empty() ? "[" : ", [") + k + "]";
    std::string near = closestName(s.name, known);
    if (near.empty()) near = closestName(s.name, former);
    throw ConfigError(where(s.line) + ": [" + s.name + "]: unknown section" +
                      (near.empty() ? "" : " (did you mean [" + near + "]?)") + "; expected " +
                      list);
  }
}

}  // namespace freeinit::config
