// The plugin's own file, asked of the dynamic loader: the library that holds this function is the
// plugin, so its path is exactly what stock tools must load to know our classes, in the build tree
// and after an install (relocated or not) alike.
#include <dlfcn.h>
#include <freeinit/mrpt_plugins/plugin_path.h>

#include <filesystem>

#ifndef FREEINIT_PLUGIN_INSTALL_PATH
#error "FREEINIT_PLUGIN_INSTALL_PATH (the configured install path of the plugin) must be defined"
#endif

namespace freeinit::mrpt_plugins {
namespace {
// An address inside this library that nothing can interpose (internal linkage).
const char kAnchor = 0;
}  // namespace

std::string pluginPath() {
  Dl_info info{};
  if (dladdr(&kAnchor, &info) != 0 && info.dli_fname != nullptr && info.dli_fname[0] != '\0') {
    std::error_code ec;
    const auto file = std::filesystem::canonical(info.dli_fname, ec);
    if (!ec) return file.string();
  }
  return FREEINIT_PLUGIN_INSTALL_PATH;
}

}  // namespace freeinit::mrpt_plugins
