// Strict reading of MRPT-style INI files, shared by the app's configuration and the other apps'
// sections: every key read is recorded, so that keys never read (typos) are errors; values are
// checked (numbers finite and complete, booleans true/false, one of a list); every message names
// the file, the section and the key.
#pragma once

#include <freeinit/types.h>

#include <map>
#include <set>
#include <string>
#include <vector>

namespace mrpt::config {
class CConfigFileBase;
}

namespace freeinit::mrpt_glue {

class IniLoader {
 public:
  /// `source` names the file in messages. `cfg` must outlive the loader.
  IniLoader(const mrpt::config::CConfigFileBase& cfg, std::string source);

  [[noreturn]] void fail(const std::string& section, const std::string& key,
                         const std::string& what) const;

  /// Whether the key is present; records it as known either way.
  bool has(const std::string& section, const std::string& key);
  /// The value's text, without a trailing comment (";" or "#") and surrounding blanks.
  std::string raw(const std::string& section, const std::string& key) const;
  /// Exactly n finite numbers separated by blanks.
  std::vector<double> numbers(const std::string& section, const std::string& key,
                              std::size_t n) const;

  // Visitor calls (unit and doc are for dumpers): x is set when the key is present.
  void operator()(const std::string& s, const std::string& k, double& x, const char* = "",
                  const char* = "");
  void operator()(const std::string& s, const std::string& k, int& x, const char* = "",
                  const char* = "");
  void operator()(const std::string& s, const std::string& k, bool& x, const char* = "",
                  const char* = "");
  void operator()(const std::string& s, const std::string& k, std::string& x, const char* = "",
                  const char* = "");
  void operator()(const std::string& s, const std::string& k, Vec3& x, const char* = "",
                  const char* = "");

  /// The index in `choices` of the key's value (case-insensitive), or `current` when absent.
  int choice(const std::string& s, const std::string& k, const std::vector<std::string>& choices,
             int current);

  /// Throws for any key of a section this loader read from that it never asked for.
  void checkUnknownKeys() const;

 private:
  const mrpt::config::CConfigFileBase& cfg_;
  std::string source_;
  std::map<std::string, std::set<std::string>> known_;
};

}  // namespace freeinit::mrpt_glue
