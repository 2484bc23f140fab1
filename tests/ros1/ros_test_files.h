// What the tests of ROS recordings share: a fresh folder for each test, a file's bytes, a text file
// written, and EXPECT_CONTAINS.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace freeinit::test {

/// A fresh, empty folder of the running test: <temp>/<suite_folder>/<suite>.<test>[/<name>]
/// (ctest runs the tests of a file in parallel processes).
inline std::string testFolder(const std::string& suite_folder, const std::string& name = "") {
  namespace fs = std::filesystem;
  const auto* test = ::testing::UnitTest::GetInstance()->current_test_info();
  fs::path d = fs::temp_directory_path() / suite_folder /
               (std::string(test->test_suite_name()) + "." + test->name());
  if (!name.empty()) d /= name;
  fs::remove_all(d);
  fs::create_directories(d);
  return d.string();
}

/// The bytes of a file ("" when it cannot be read).
inline std::string fileBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

/// Writes `text` to `path`; returns `path`.
inline std::string writeText(const std::string& path, const std::string& text) {
  std::ofstream(path) << text;
  return path;
}

}  // namespace freeinit::test

#define EXPECT_CONTAINS(haystack, needle) \
  EXPECT_NE(std::string(haystack).find(needle), std::string::npos) << (haystack)
