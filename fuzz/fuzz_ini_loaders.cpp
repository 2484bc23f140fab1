// Fuzz harness: the configuration files. Byte 0 selects the loader, the rest is the file:
//   0: freeinit's configuration (loadAppConfig: the INI parser and every section declaration)
//   1: freeinit-import-bag's ([bag_import] + [extrinsics], loadBagImportSettings)
//   2: a freeinit-sim scenario (sim::loadScenarioIni)
//   3: freeinit-icp-slam's [freeinit_scan] (loadScanSliceParams, other sections skipped)
//   else: the parser alone (config::IniFile::parse)
// Every loader takes a path: the input is written to a file first. Invariants: an error is one
// line naming the file; a configuration that loads echoes (dumpAppConfig) to text that loads
// again to the same echo, with the current key names only.
#include <freeinit/app_support/app_config.h>
#include <freeinit/app_support/icp_slam_bridge.h>
#include <freeinit/io/config_section.h>
#include <freeinit/io/ini_file.h>
#include <freeinit/sim/scenario_ini.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "bag_import_app.h"
#include "harness.h"

namespace freeinit::fuzz {
namespace {

bool save(const std::string& path, const std::uint8_t* data, std::size_t size) {
  FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) return false;
  const bool ok = std::fwrite(data, 1, size, f) == size;
  std::fclose(f);
  return ok;
}

std::string echo(const app_support::AppConfig& c) {
  std::ostringstream os;
  app_support::dumpAppConfig(c, os);
  return os.str();
}

std::string load(int loader, const std::string& path, const std::uint8_t* data, std::size_t size) {
  switch (loader) {
    case 0: {
      std::vector<std::string> notices;  // keys under their former names: read, not printed
      const std::string first = echo(app_support::loadAppConfig(path, &notices));
      const std::string again_path = path + ".echo.ini";
      save(again_path, reinterpret_cast<const std::uint8_t*>(first.data()), first.size());
      notices.clear();
      if (echo(app_support::loadAppConfig(again_path, &notices)) != first)
        broken("the echoed configuration does not load back to itself");
      if (!notices.empty()) broken("the echoed configuration uses a former key name");
      return "ok: freeinit configuration";
    }
    case 1:
      apps::loadBagImportSettings(path);
      return "ok: bag import settings";
    case 2: {
      const sim::ScenarioConfig sc = sim::loadScenarioIni(path);
      return "ok: scenario " + sc.name;
    }
    case 3:
      app_support::loadScanSliceParams(path);
      return "ok: scan slice";
    default: {
      const config::IniFile ini =
          config::IniFile::parse(std::string_view(reinterpret_cast<const char*>(data), size), path);
      return "ok: " + std::to_string(ini.sections().size()) + " sections";
    }
  }
}

}  // namespace

std::string fuzzOne(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return "error: no loader selector";
  static const std::string path = (std::filesystem::temp_directory_path() /
                                   ("freeinit_fuzz_ini_" + std::to_string(getpid()) + ".ini"))
                                      .string();
  const int loader = data[0] % 5;
  if (!save(path, data + 1, size - 1)) return "error: cannot write " + path;
  try {
    return load(loader, path, data + 1, size - 1);
  } catch (const std::exception& e) {
    const std::string m = e.what();
    if (m.find('\n') != std::string::npos) broken("a multi-line error");
    if (m.rfind(path, 0) != 0) broken("an error that does not start with the file name");
    return "error: " + m;
  }
}

}  // namespace freeinit::fuzz
