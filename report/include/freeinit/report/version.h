// The project version the evaluation apps report (--version).
#pragma once

namespace freeinit::report {

/// "MAJOR.MINOR.PATCH" of the build (the CMake project version).
const char* version();

}  // namespace freeinit::report
