#include <freeinit/atomic_file.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace freeinit {

void writeFileAtomically(const std::string& path, const std::function<void(std::ostream&)>& fill,
                         bool binary) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream f(tmp, binary ? std::ios::binary | std::ios::trunc : std::ios::trunc);
    if (!f) throw std::runtime_error(path + ": cannot create " + tmp);
    try {
      fill(f);
    } catch (...) {
      f.close();
      std::remove(tmp.c_str());
      throw;
    }
    f.flush();
    if (!f) {
      f.close();
      std::remove(tmp.c_str());
      throw std::runtime_error(path + ": write error");
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
