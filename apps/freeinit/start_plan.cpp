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
