#include <freeinit/io/config_section.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <iomanip>
#include <limits>
#include <ostream>
#include <sstream>

namespace freeinit::config {

bool Range::contains(double x) const {
  if (!std::isfinite(x)) return false;
  if (lo_open ? !(x > lo) : !(x >= lo)) return false;
  if (hi_open ? !(x < hi) : !(x <= hi)) return false;
  return true;
}

std::string Range::text() const {
  const bool has_lo = std::isfinite(lo), has_hi = std::isfinite(hi);
  if (!has_lo && !has_hi) return "any";
  if (!has_hi) return (lo_open ? "> " : ">= ") + formatNumber(lo);
  if (!has_lo) return (hi_open ? "< " : "<= ") + formatNumber(hi);
  return std::string(lo_open ? "(" : "[") + formatNumber(lo) + ", " + formatNumber(hi) +
         (hi_open ? ")" : "]");
}

Range any() { return Range{}; }
Range atLeast(double lo) {
  return Range{lo, std::numeric_limits<double>::infinity(), false, false};
}
Range above(double lo) { return Range{lo, std::numeric_limits<double>::infinity(), true, false}; }
Range between(double lo, double hi) { return Range{lo, hi, false, false}; }
Range aboveUpTo(double lo, double hi) { return Range{lo, hi, true, false}; }

std::string parseNumber(std::string_view text, double& x) {
  const bool chars_ok = !text.empty() && std::all_of(text.begin(), text.end(), [](char c) {
    return std::isdigit(static_cast<unsigned char>(c)) || c == '+' || c == '-' || c == '.' ||
           c == 'e' || c == 'E';
  });
  if (chars_ok) {
    const std::string s(text);
    char* end = nullptr;
    errno = 0;
    const double v = std::strtod(s.c_str(), &end);
    if (end == s.c_str() + s.size() && end != s.c_str()) {
      if (!std::isfinite(v) || errno == ERANGE)
        return quote(text) + " is out of the range of a double";
      x = v;
      return "";
    }
  }
  return quote(text) + " is not a number";
}

std::string parseInteger(std::string_view text, long double lo, long double hi, long double& x) {
  std::string_view digits = text;
  if (!digits.empty() && (digits.front() == '+' || digits.front() == '-')) digits.remove_prefix(1);
  if (digits.empty() || !std::all_of(digits.begin(), digits.end(), [](char c) {
        return std::isdigit(static_cast<unsigned char>(c));
      })) {
    double d = 0;
    return parseNumber(text, d).empty() ? quote(text) + " is not a whole number"
                                        : quote(text) + " is not a number";
  }
  if (digits.size() > 30) return quote(text) + " is out of range";
  const std::string s(text);
  const long double v = std::strtold(s.c_str(), nullptr);
  if (v < lo || v > hi) {
    std::ostringstream os;
    os << quote(text) << " is out of range for this key (" << std::setprecision(20) << lo << " to "
       << hi << ")";
    return os.str();
  }
  x = v;
  return "";
}

std::string parseNumbers(std::string_view text, std::size_t n, std::vector<double>& out) {
  out.clear();
  std::size_t i = 0;
  while (i < text.size()) {
    while (i < text.size() && (text[i] == ' ' || text[i] == '\t' || text[i] == ',')) ++i;
    if (i == text.size()) break;
    std::size_t j = i;
    while (j < text.size() && text[j] != ' ' && text[j] != '\t' && text[j] != ',') ++j;
    double x = 0;
    if (std::string err = parseNumber(text.substr(i, j - i), x); !err.empty()) return err;
    out.push_back(x);
    i = j;
  }
  if (out.size() != n)
    return "expected " + std::to_string(n) + (n == 1 ? " number" : " numbers separated by blanks") +
           ", got " + std::to_string(out.size());
  return "";
}

std::string parseBool(std::string_view text, bool& x) {
  for (const char* t : {"true", "1", "yes", "on"})
    if (sameName(text, t)) {
      x = true;
      return "";
    }
  for (const char* f : {"false", "0", "no", "off"})
    if (sameName(text, f)) {
      x = false;
      return "";
    }
  return quote(text) + " is not a boolean (true/false)";
}

bool Checker::has(const std::string& key) const {
  if (!file_) return false;
  const IniSection* s = file_->section(section_);
  return s && s->find(key);
}

void Checker::fail(const std::string& key, const std::string& what) const {
  if (file_) file_->fail(section_, key, what);
  throw ConfigError("configuration key " + section_ + "." + key + ": " + what);
}

void dumpSectionHeader(std::ostream& out, const std::string& name, const std::string& doc,
                       const std::vector<KeyInfo>& keys) {
  out << "[" << name << "]\n";
  if (!doc.empty()) out << "; " << doc << "\n";
  std::vector<std::string> readers;
  for (const KeyInfo& k : keys) {
    std::size_t begin = 0;
    while (begin < k.readers.size()) {
      const std::size_t comma = std::min(k.readers.find(',', begin), k.readers.size());
      std::size_t b = begin, e = comma;
      while (b < e && k.readers[b] == ' ') ++b;
      while (e > b && k.readers[e - 1] == ' ') --e;
      const std::string reader = k.readers.substr(b, e - b);
      if (!reader.empty() && std::find(readers.begin(), readers.end(), reader) == readers.end())
        readers.push_back(reader);
      begin = comma + 1;
    }
  }
  if (readers.empty()) return;
  out << "; read by:";
  for (std::size_t i = 0; i < readers.size(); ++i) out << (i ? ", " : " ") << readers[i];
  out << "\n";
}

std::vector<KeyRename> formerNames(const std::vector<const SectionBase*>& sections) {
  std::vector<KeyRename> out;
  for (const SectionBase* s : sections)
    for (const KeyInfo& k : s->keys())
      for (const FormerName& f : k.former) out.push_back({f.section, f.key, s->name(), k.name});
  return out;
}

std::vector<std::string> formerSectionNames(const std::vector<const SectionBase*>& sections) {
  std::vector<std::string> out;
  for (const KeyRename& r : formerNames(sections)) {
    const bool current = std::any_of(sections.begin(), sections.end(), [&](const SectionBase* s) {
      return sameName(s->name(), r.from_section);
    });
    const bool listed = std::any_of(out.begin(), out.end(), [&](const std::string& name) {
      return sameName(name, r.from_section);
    });
    if (!current && !listed) out.push_back(r.from_section);
  }
  return out;
}

IniFile renameFormerKeys(const IniFile& ini, const std::vector<const SectionBase*>& sections,
                         std::vector<std::string>& notices) {
  return ini.withRenames(formerNames(sections), formerSectionNames(sections), notices);
}

namespace detail {

void dumpLine(std::ostream& out, const KeyInfo& k, const std::string& value, bool commented) {
  // Keys aligned as in the shipped INI files; the longest key name is 31 characters.
  constexpr std::size_t kKeyWidth = 32, kValueWidth = 14;
  std::string line = (commented ? ";" : "") + k.name;
  line.resize(std::max(line.size() + 1, kKeyWidth), ' ');
  line += "= " + value;
  line.resize(std::max(line.size() + 1, kKeyWidth + 2 + kValueWidth), ' ');
  line += "; [" + k.unit + "] " + k.doc;
  if (!k.accepted.empty() && k.unit != "bool") line += " (accepted: " + k.accepted + ")";
  if (!k.readers.empty()) line += " (" + k.readers + ")";
  out << line << "\n";
}

std::string outOfRange(const std::string& value, const Range& r, const std::string& unit) {
  return value + " is out of range: accepted " + r.text() +
         (unit.empty() || unit == "-" ? "" : " " + unit);
}

void unknownKey(const IniFile& ini, const std::string& section, const std::string& key,
                const std::vector<std::string>& known) {
  const std::string near = closestName(key, known);
  ini.fail(section, key, "unknown key" + (near.empty() ? "" : " (did you mean " + near + "?)"));
}

}  // namespace detail
}  // namespace freeinit::config
