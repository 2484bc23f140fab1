// The INI text every configuration file of the project is read from: `[section]` headers,
// `key = value` lines, comments (lines starting with ';' or '#', and the rest of a line after a
// ';' or '#' in a value), blank lines. Nothing else: no variable expansion (`${VAR}`), no
// `@include`/`@define`, no keys outside a section, no key given twice, no section given twice,
// no binary data. Section and key names compare case-insensitively (as MRPT's INI files do).
// Every error is one line, "file:line: what" (ConfigError).
#pragma once

#include <cstddef>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace freeinit::config {

/// A configuration error: one line naming the file, the line, and the section and key when the
/// error concerns one.
class ConfigError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// Case-insensitive comparison of section and key names.
bool sameName(std::string_view a, std::string_view b);
/// The candidate closest to `name` when it is a likely misspelling of it (a few letters off),
/// else "": for "did you mean" hints.
std::string closestName(std::string_view name, const std::vector<std::string>& candidates);
/// `text` quoted for a message, shortened when long.
std::string quote(std::string_view text);

struct IniEntry {
  std::string key;    ///< as written
  std::string value;  ///< without the comment and surrounding blanks; one pair of "" removed
  int line = 0;       ///< 1-based; 0 when the entry does not come from a file
  /// "[section] key" as the file gives it, when withRenames() moved it from a former name ("":
  /// where it stands); messages about the entry name both.
  std::string given_as;
};

struct IniSection {
  std::string name;
  int line = 0;  ///< of the [header]; 0 when not from a file
  /// Whether its lines were read (false: a section of another program, see ParseOptions).
  bool checked = true;
  std::vector<IniEntry> entries;
  const IniEntry* find(std::string_view key) const;
};

/// A key's move from an earlier layout: [from_section] from_key is now [to_section] to_key.
struct KeyRename {
  std::string from_section, from_key;
  std::string to_section, to_key;
};

struct ParseOptions {
  /// When not empty, only these sections' lines are read and checked; the lines of any other
  /// section are skipped (sections of another program sharing the file, e.g. MRPT's
  /// [MappingApplication] in icp_slam.ini). Their [headers] are still read.
  std::vector<std::string> only_sections;
};

class IniFile {
 public:
  /// Largest file load() accepts [bytes]: configuration files are a few kB.
  static constexpr std::size_t kMaxBytes = 1 << 20;

  IniFile() = default;
  explicit IniFile(std::string source) : source_(std::move(source)) {}

  /// Parses INI text; `source` names it in messages. Throws ConfigError.
  static IniFile parse(std::string_view text, std::string source, const ParseOptions& = {});
  /// Reads and parses a file. Throws ConfigError (not found, a directory, unreadable, too large,
  /// not text, malformed).
  static IniFile load(const std::string& path, const ParseOptions& = {});

  const std::string& source() const { return source_; }
  const std::vector<IniSection>& sections() const { return sections_; }
  const IniSection* section(std::string_view name) const;
  /// Adds a section built in code (e.g. from another program's parsed configuration); its
  /// values are cleaned and checked as parse() does. Throws ConfigError if it exists already.
  void add(IniSection section);

  /// This file with the keys given under a former name moved to their current section and name
  /// (`renames`), keeping their values and lines; one notice per moved key appended to
  /// `notices`: "file:line: [velocimeter] doppler_sigma is now [doppler] doppler_sigma (the old
  /// name is read for now)". A section named in `retired` (one that only former names use) must
  /// hold only keys that move: another key there is an unknown key; retired sections are not in
  /// the result. Throws ConfigError for a key given under two of its names (e.g. the former and
  /// the current one), naming both.
  IniFile withRenames(const std::vector<KeyRename>& renames,
                      const std::vector<std::string>& retired,
                      std::vector<std::string>& notices) const;

  /// Throws ConfigError naming the first section whose name is not in `known` nor in `former`
  /// (a misspelt section must not silently leave its keys at their defaults). `former`: names
  /// of an earlier layout, still accepted (see withRenames()), not listed as expected.
  void requireKnownSections(const std::vector<std::string>& known,
                            const std::vector<std::string>& former = {}) const;

  /// "file:line" (or "file" when line is 0): the prefix of every message about this file.
  std::string where(int line) const;
  /// Throws ConfigError "file:line: [section] key: what" (the key's line when the section has
  /// it, else the section's).
  [[noreturn]] void fail(const std::string& section, const std::string& key,
                         const std::string& what) const;

 private:
  std::string source_;
  std::vector<IniSection> sections_;
};

/// A value as an INI line holds it: the text after '=' without its comment and blanks, one pair
/// of surrounding double quotes removed. Returns an error (empty when fine): variable expansion
/// such as `${VAR}` is refused.
std::string cleanValue(std::string_view raw, std::string& value);

}  // namespace freeinit::config
