// What the tests of freeinit on ROS recordings share: one run of the app and the files it wrote.
#pragma once

#include <filesystem>
#include <map>
#include <optional>
#include <sstream>
#include <string>

#include "free_init_app.h"
#include "ros_test_files.h"

namespace freeinit::test {

/// What a run of freeinit left.
struct AppRun {
  std::map<std::string, std::string> files;  ///< name -> bytes (start folders: "<start>/<name>")
  std::string log;
};

/// freeinit with `ini` on `input` into `out` (no progress bar, no configuration echo), once at
/// `start` or every `every` s (0: once). The files are those of `out` and its start folders but
/// the simple map (it holds the observations' source names) and starts.md (it names the input).
inline AppRun runFreeInit(const std::string& ini, const std::string& input, const std::string& out,
                          std::optional<double> start = std::nullopt, double every = 0) {
  namespace fs = std::filesystem;
  apps::FreeInitApp app;
  app.params.config_file = ini;
  app.params.rawlog = input;
  app.params.out_dir = out;
  app.params.progress = false;
  app.params.echo_config = false;
  app.params.start = start;
  app.params.every = every;
  std::ostringstream log;
  app.run(log);
  AppRun r;
  r.log = log.str();
  for (const auto& f : fs::recursive_directory_iterator(out)) {
    const std::string name = fs::relative(f.path(), out).string();
    if (!f.is_regular_file() || f.path().extension() == ".simplemap" ||
        f.path().filename() == "starts.md")
      continue;
    r.files[name] = fileBytes(f.path().string());
  }
  return r;
}

}  // namespace freeinit::test
