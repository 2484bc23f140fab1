#include "start_plan.h"

#include <freeinit/input_checks.h>
#include <freeinit/mrpt_plugins/rawlog_reader.h>

#include <cmath>
#include <fstream>
#include <sstream>

namespace freeinit::apps {

double startTime(double value, double first) {
  return value > kUnixStampThreshold ? value : first + value;
}

std::string everyProblem(double every, double window) {
  const double open = window / every;
  if (!(open > static_cast<double>(kMaxOpenStarts))) return "";
  std::ostringstream os;
  os << "--every " << every << ": starts " << every << " s apart keep about "
     << static_cast<long long>(std::ceil(open)) << " initializations open at once (each holds its "
     << window << " s window, [window] duration); at most " << kMaxOpenStarts << ": give --every "
     << window / static_cast<double>(kMaxOpenStarts) << " or more";
  return os.str();
}

std::string startsProblem(const std::vector<double>& t, double window, const std::string& source) {
  if (t.size() > kMaxStarts)
    return source + ": " + std::to_string(t.size()) + " starts, more than the " +
           std::to_string(kMaxStarts) + " one run makes: split the file";
  for (std::size_t i = 0, j = 0; i < t.size(); ++i) {
    while (j < t.size() && t[j] < t[i] + window) ++j;
    if (j - i > kMaxOpenStarts) {
      std::ostringstream os;
      os << source << ": " << j - i << " starts within one window (" << window
         << " s, [window] duration) from " << t[i] << " on: at most " << kMaxOpenStarts
         << " initializations are open at once";
      return os.str();
    }
  }
  return "";
}

int folderDecimals(const std::vector<double>& offsets) {
  constexpr int kMin = 3, kMax = 9;
  for (int d = kMin; d < kMax; ++d) {
    const double scale = std::pow(10.0, d);
    bool distinct = true;
    for (std::size_t i = 1; i < offsets.size() && distinct; ++i)
      distinct = std::llround(offsets[i] * scale) != std::llround(offsets[i - 1] * scale);
    if (distinct) return d;
  }
  return kMax;
}

std::vector<double> readStartsFile(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw mrpt_plugins::InputError(path + ": cannot open the starts file");
  std::vector<double> out;
  std::string line;
  for (int n = 1; std::getline(f, line); ++n) {
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.erase(hash);
    std::istringstream is(line);
    double v = 0;
    if (!(is >> v)) {
      if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
      throw mrpt_plugins::InputError(path + ": line " + std::to_string(n) + ": '" + line +
                                     "' is not a number");
    }
    std::string rest;
    if (is >> rest)
      throw mrpt_plugins::InputError(path + ": line " + std::to_string(n) + ": one start per line");
    if (!std::isfinite(v) || v < 0)
      throw mrpt_plugins::InputError(path + ": line " + std::to_string(n) +
                                     ": a start must be >= 0");
    if (!out.empty() && !(v > out.back()))
      throw mrpt_plugins::InputError(path + ": line " + std::to_string(n) +
                                     ": starts must increase (after " +
                                     input::formatStamp(out.back()) + ")");
    out.push_back(v);
  }
  if (out.empty()) throw mrpt_plugins::InputError(path + ": no start in the file");
  return out;
}

}  // namespace freeinit::apps
