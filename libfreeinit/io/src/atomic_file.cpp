#include <freeinit/io/atomic_file.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace freeinit {

void writeFileAtomically(const std::string& path, const std::function<void(std::ostream&)>& fill,
                         bool binary) {
  const std::string tmp = path + ".tmp";
  {
    errno = 0;
    std::ofstream f(tmp, binary ? std::ios::binary | std::ios::trunc : std::ios::trunc);
    if (!f)
      throw std::runtime_error(path + ": cannot create " + tmp +
                               (errno != 0 ? ": " + std::string(std::strerror(errno)) : ""));
    // The system's reason (e.g. "No space left on device") is errno of the write that failed:
    // inside fill() when a buffer was flushed there, else in the final flush or close.
    errno = 0;
    try {
      fill(f);
    } catch (...) {
      f.close();
      std::remove(tmp.c_str());
      throw;
    }
    if (f) {
      errno = 0;
      f.flush();
      if (f) f.close();
    }
    if (!f) {
      const int err = errno;
      f.close();
      std::remove(tmp.c_str());
      throw std::runtime_error(path + ": write error" +
                               (err != 0 ? ": " + std::string(std::strerror(err)) : ""));
    }
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::remove(tmp.c_str());
    throw std::runtime_error(path + ": cannot rename the temporary file: " + ec.message());
  }
}

}  // namespace freeinit
