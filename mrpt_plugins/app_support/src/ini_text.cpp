#include "ini_text.h"

namespace freeinit::app_support {

std::string_view firstIniLine(std::string_view text) {
  std::size_t pos = 0;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(pos, end - pos);
    pos = end + 1;
    const auto b = line.find_first_not_of(" \t\r");
    if (b == std::string_view::npos) continue;
    line.remove_prefix(b);
    if (line[0] == ';' || line[0] == '#') continue;
    return line.substr(0, line.find_last_not_of(" \t\r") + 1);
  }
  return {};
}

}  // namespace freeinit::app_support
