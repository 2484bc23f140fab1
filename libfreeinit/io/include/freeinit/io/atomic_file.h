// Writing a file so that readers see it complete or not at all: it is written to "<path>.tmp" and
// renamed onto `path` when complete. Standard library only; used by the core tools, the simulator
// and the MRPT glue alike.
#pragma once

#include <functional>
#include <iosfwd>
#include <string>

namespace freeinit {

/// Writes through `fill` into "<path>.tmp", then renames it onto `path`.
/// Throws std::runtime_error (naming the path) on any I/O error; the target is then untouched and
/// the temporary file removed. An exception thrown by `fill` is passed on the same way.
void writeFileAtomically(const std::string& path, const std::function<void(std::ostream&)>& fill,
                         bool binary = false);

}  // namespace freeinit
