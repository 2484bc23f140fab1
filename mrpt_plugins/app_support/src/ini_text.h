// What both file-kind checks (file_kind.cpp, output_file_kind.cpp) look at in a text that may be
// an INI file.
#pragma once

#include <string_view>

namespace freeinit::app_support {

/// The first line of `text` that is neither blank nor a comment (';' or '#'), without its leading
/// and trailing blanks; empty when there is none.
std::string_view firstIniLine(std::string_view text);

}  // namespace freeinit::app_support
