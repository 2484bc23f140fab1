// Where the MRPT plugin is, for stock MRPT tools: `rawlog-edit -p FILE`, `rawlog-grabber -p FILE`
// and `RawLogViewer -l FILE` take the plugin's file (MRPT 2.5.8 has no plugin folder and no
// environment variable that loads one). Every app prints it with --plugin-path.
#pragma once

#include <string>

namespace freeinit::mrpt_plugins {

/// The plugin's file name: libfreeinit_mrpt_plugins.so.
inline constexpr const char* kPluginFileName = "libfreeinit_mrpt_plugins.so";

/// The absolute path of the plugin library this process has loaded (the apps link it): the build
/// tree's before `cmake --install`, the installed one after (`<prefix>/<libdir>/freeinit/`),
/// wherever the install folder was moved. Falls back to the configured install path when the
/// loader cannot tell.
std::string pluginPath();

}  // namespace freeinit::mrpt_plugins
