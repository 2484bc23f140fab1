#include <freeinit/mrpt/IniLoader.h>
#include <mrpt/config/CConfigFileBase.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace freeinit::mrpt_glue {
namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

}  // namespace

IniLoader::IniLoader(const mrpt::config::CConfigFileBase& cfg, std::string source)
    : cfg_(cfg), source_(std::move(source)) {}

void IniLoader::fail(const std::string& section, const std::string& key,
                     const std::string& what) const {
  throw std::invalid_argument(source_ + ": [" + section + "] " + key + ": " + what);
}

bool IniLoader::has(const std::string& s, const std::string& k) {
  known_[s].insert(lower(k));
  return cfg_.keyExists(s, k);
}

std::string IniLoader::raw(const std::string& s, const std::string& k) const {
  std::string v = cfg_.read_string(s, k, "", false);
  // Strip trailing comments and blanks (CConfigFile keeps text after the value in some cases).
  for (const char* c : {";", "#"}) {
    if (auto p = v.find(c); p != std::string::npos) v.erase(p);
  }
  while (!v.empty() && std::isspace(static_cast<unsigned char>(v.back()))) v.pop_back();
  while (!v.empty() && std::isspace(static_cast<unsigned char>(v.front()))) v.erase(0, 1);
  return v;
}

std::vector<double> IniLoader::numbers(const std::string& s, const std::string& k,
                                       std::size_t n) const {
  std::istringstream is(raw(s, k));
  std::vector<double> out;
  std::string tok;
  while (is >> tok) {
    try {
      std::size_t used = 0;
      out.push_back(std::stod(tok, &used));
      if (used != tok.size()) throw std::invalid_argument(tok);
    } catch (const std::exception&) {
      fail(s, k, "'" + tok + "' is not a number");
    }
    if (!std::isfinite(out.back())) fail(s, k, "'" + tok + "' is not finite");
  }
  if (out.size() != n)
    fail(s, k, "expected " + std::to_string(n) + " number(s), got " + std::to_string(out.size()));
  return out;
}

void IniLoader::operator()(const std::string& s, const std::string& k, double& x, const char*,
                           const char*) {
  if (has(s, k)) x = numbers(s, k, 1)[0];
}

void IniLoader::operator()(const std::string& s, const std::string& k, int& x, const char*,
                           const char*) {
  if (!has(s, k)) return;
  const double d = numbers(s, k, 1)[0];
  if (d != std::floor(d) || std::abs(d) > 1e9) fail(s, k, "expected an integer");
  x = static_cast<int>(d);
}

void IniLoader::operator()(const std::string& s, const std::string& k, bool& x, const char*,
                           const char*) {
  if (!has(s, k)) return;
  const std::string v = lower(raw(s, k));
  if (v == "true" || v == "1" || v == "yes" || v == "on") {
    x = true;
  } else if (v == "false" || v == "0" || v == "no" || v == "off") {
    x = false;
  } else {
    fail(s, k, "'" + v + "' is not a boolean (true/false)");
  }
}

void IniLoader::operator()(const std::string& s, const std::string& k, std::string& x, const char*,
                           const char*) {
  if (has(s, k)) x = raw(s, k);
}

void IniLoader::operator()(const std::string& s, const std::string& k, Vec3& x, const char*,
                           const char*) {
  if (!has(s, k)) return;
  const auto v = numbers(s, k, 3);
  x = Vec3(v[0], v[1], v[2]);
}

int IniLoader::choice(const std::string& s, const std::string& k,
                      const std::vector<std::string>& choices, int current) {
  if (!has(s, k)) return current;
  const std::string v = lower(raw(s, k));
  for (std::size_t i = 0; i < choices.size(); ++i)
    if (v == lower(choices[i])) return static_cast<int>(i);
  std::string all;
  for (const auto& c : choices) all += (all.empty() ? "'" : ", '") + c + "'";
  fail(s, k, "'" + v + "' is not one of " + all);
}

void IniLoader::checkUnknownKeys() const {
  for (const auto& [section, keys] : known_) {
    std::vector<std::string> present;
    cfg_.getAllKeys(section, present);
    for (const auto& k : present) {
      if (keys.count(lower(k)) == 0) fail(section, k, "unknown key");
    }
  }
}

}  // namespace freeinit::mrpt_glue
