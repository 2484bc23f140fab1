// The configuration mechanism of the core (no MRPT): the INI parser, the key declarations
// (loading, validation, echo) of the estimator's sections, the former names of their keys, and
// the window in seconds.
#include <freeinit/config.h>
#include <freeinit/free_init.h>
#include <freeinit/io/config_section.h>
#include <freeinit/io/ini_file.h>
#include <freeinit/io/number_format.h>
#include <freeinit/sim/simulator.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

using namespace freeinit;
using config::ConfigError;
using config::IniFile;
namespace fs = std::filesystem;

namespace {

// The message of the ConfigError `f` throws ("" and a test failure when it throws none or
// another type). Every configuration error is one line.
std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.find('\n'), std::string::npos) << "not one line: " << what;
    return what;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "not a ConfigError: " << e.what();
    return "";
  }
  ADD_FAILURE() << "no error";
  return "";
}

#define EXPECT_CONTAINS(haystack, needle)                                                      \
  do {                                                                                         \
    const std::string h_ = (haystack);                                                         \
    EXPECT_NE(h_.find(needle), std::string::npos) << h_ << "\n  should contain: " << (needle); \
  } while (0)

FreeInitConfig loadCore(const std::string& text, std::vector<std::string>* notices = nullptr) {
  FreeInitConfig c;
  const IniFile ini = IniFile::parse(text, "t.ini");
  ini.requireKnownSections(FreeInitConfig::sectionNames(), FreeInitConfig::formerSectionNames());
  std::vector<std::string> ignored;
  c.load(ini, notices ? notices : &ignored);
  return c;
}

std::string dumpOf(const FreeInitConfig& c) {
  std::ostringstream os;
  c.dump(os);
  return os.str();
}

}  // namespace

TEST(IniFile, ReadsSectionsKeysAndEveryCommentForm) {
  const IniFile ini = IniFile::parse(
      "\xEF\xBB\xBF; a comment\n# another\n\n[One]\nkey = value ; inline\nQuoted = \"a b\"  # x\n"
      "empty =\n  spaced   =   1 2 3  \n[two]\nk=v\r\n",
      "t.ini");
  ASSERT_EQ(ini.sections().size(), 2u);
  const config::IniSection* one = ini.section("one");  // names compare case-insensitively
  ASSERT_NE(one, nullptr);
  EXPECT_EQ(one->line, 4);
  ASSERT_EQ(one->entries.size(), 4u);
  EXPECT_EQ(one->find("KEY")->value, "value");
  EXPECT_EQ(one->find("key")->line, 5);
  EXPECT_EQ(one->find("quoted")->value, "a b");
  EXPECT_EQ(one->find("empty")->value, "");
  EXPECT_EQ(one->find("spaced")->value, "1 2 3");
  EXPECT_EQ(ini.section("TWO")->find("k")->value, "v");
}

TEST(IniFile, EveryMalformedLineIsOneErrorNamingFileAndLine) {
  const auto parse = [](const std::string& text) { IniFile::parse(text, "f.ini"); };
  EXPECT_CONTAINS(errorOf([&] { parse("[a]\nk = 1\nk = 2\n"); }),
                  "f.ini:3: [a] k: key given twice (first at line 2)");
  EXPECT_CONTAINS(errorOf([&] { parse("[a]\nK = 1\nk = 2\n"); }),
                  "f.ini:3: [a] k: key given twice");
  EXPECT_CONTAINS(errorOf([&] { parse("[a]\n[b]\n[A]\n"); }),
                  "f.ini:3: [A]: section given twice (first at line 1)");
  EXPECT_CONTAINS(errorOf([&] { parse("k = 1\n"); }), "f.ini:1: k: key outside a [section]");
  EXPECT_CONTAINS(errorOf([&] { parse("[a]\njust words\n"); }),
                  "f.ini:2: [a]: 'just words': expected 'key = value'");
  EXPECT_CONTAINS(errorOf([&] { parse("[a\n"); }), "f.ini:1: malformed section header");
  EXPECT_CONTAINS(errorOf([&] { parse("[]\n"); }), "f.ini:1: empty section name");
  EXPECT_CONTAINS(errorOf([&] { parse("[a] b\n"); }), "f.ini:1: [a]: unexpected text");
  EXPECT_CONTAINS(errorOf([&] { parse("[a]\nmy key = 1\n"); }),
                  "f.ini:2: [a] 'my key' is not a key");
  EXPECT_CONTAINS(errorOf([&] { parse("[a]\n@include other.ini\n"); }),
                  "f.ini:2: [a]: '@include other.ini': directives such as @include");
  // Binary data (e.g. a rawlog given as the INI) is named, never printed.
  const std::string gz("\x1f\x8b\x08\x00[a]\n", 8);
  const std::string e = errorOf([&] { parse(gz); });
  EXPECT_CONTAINS(e, "f.ini:1: binary data (byte 0x1f): not an INI text file");
  EXPECT_EQ(e.find('\x8b'), std::string::npos);
}

// MRPT's INI reader expands ${VAR} (and throws a multi-line exception with a call stack on an
// unclosed one, as in the fuzzer's reproducer "[input]\nimu_label = ${FOO"); ours expands nothing
// and says so on one line.
TEST(IniFile, VariablesAreNotExpanded) {
  EXPECT_CONTAINS(errorOf([] { IniFile::parse("[input]\nimu_label = ${FOO\n", "x.ini"); }),
                  "x.ini:2: [input] imu_label: '${FOO': variables and expressions ($...{...}) are "
                  "not expanded");
  EXPECT_CONTAINS(errorOf([] { IniFile::parse("[a]\nk = $env{HOME}/x\n", "x.ini"); }),
                  "x.ini:2: [a] k: '$env{HOME}/x': variables");
}

TEST(IniFile, LoadNamesMissingFilesDirectoriesAndHugeFiles) {
  const fs::path d = fs::temp_directory_path() / "freeinit_test_config";
  fs::create_directories(d);
  EXPECT_CONTAINS(errorOf([&] { IniFile::load((d / "none.ini").string()); }),
                  "none.ini: configuration file not found");
  EXPECT_CONTAINS(errorOf([&] { IniFile::load(d.string()); }),
                  "is a directory, not a configuration file");
  const std::string big = (d / "big.ini").string();
  {
    std::ofstream f(big);
    f << "[a]\n" << std::string(IniFile::kMaxBytes, ';') << "\n";
  }
  EXPECT_CONTAINS(errorOf([&] { IniFile::load(big); }), "too large for a configuration file");
  const std::string only = (d / "only.ini").string();
  {
    std::ofstream f(only);
    f << "[mine]\nk = 1\n[theirs]\n${whatever MRPT reads\n";
  }
  const IniFile ini = IniFile::load(only, {{"mine"}});  // other sections are not read
  EXPECT_EQ(ini.section("mine")->find("k")->value, "1");
  EXPECT_FALSE(ini.section("theirs")->checked);
}

TEST(FreeInitConfigIni, MisspeltSectionsAndKeysAreErrorsWithAHint) {
  EXPECT_CONTAINS(errorOf([] { loadCore("[dopler]\ndoppler_sigma = 0.1\n"); }),
                  "t.ini:1: [dopler]: unknown section (did you mean [doppler]?)");
  EXPECT_CONTAINS(errorOf([] { loadCore("[doppler]\n\ndopler_sigma = 0.1\n"); }),
                  "t.ini:3: [doppler] dopler_sigma: unknown key (did you mean doppler_sigma?)");
  EXPECT_CONTAINS(errorOf([] { loadCore("[doppler]\nxyz = 1\n"); }),
                  "t.ini:2: [doppler] xyz: unknown key");
  // In a section of the earlier layout, the same (its keys as they were named there).
  EXPECT_CONTAINS(errorOf([] { loadCore("[velocimetr]\ndoppler_sigma = 0.1\n"); }),
                  "t.ini:1: [velocimetr]: unknown section (did you mean [velocimeter]?)");
  EXPECT_CONTAINS(errorOf([] { loadCore("[velocimeter]\n\ndopler_sigma = 0.1\n"); }),
                  "t.ini:3: [velocimeter] dopler_sigma: unknown key (did you mean doppler_sigma?)");
  EXPECT_CONTAINS(errorOf([] { loadCore("[velocimeter]\nxyz = 1\n"); }),
                  "t.ini:2: [velocimeter] xyz: unknown key");
  // A key of another section is not taken for its own: [window] has only duration now.
  EXPECT_CONTAINS(errorOf([] { loadCore("[window]\nrefinement_pases = 1\n"); }),
                  "t.ini:2: [window] refinement_pases: unknown key");
}

TEST(FreeInitConfigIni, MalformedValuesNameTheKeyAndWhatWasExpected) {
  EXPECT_CONTAINS(errorOf([] { loadCore("[paper_bootstrap]\npoints = ten\n"); }),
                  "t.ini:2: [paper_bootstrap] points: 'ten' is not a number");
  EXPECT_CONTAINS(errorOf([] { loadCore("[start]\npoints = 2.5\n"); }),
                  "[start] points: '2.5' is not a whole number");
  EXPECT_CONTAINS(errorOf([] { loadCore("[imu]\ngyro_sigma = 0x10\n"); }),
                  "[imu] gyro_sigma: '0x10' is not a number");
  EXPECT_CONTAINS(errorOf([] { loadCore("[imu]\ngyro_sigma = nan\n"); }),
                  "[imu] gyro_sigma: 'nan' is not a number");
  EXPECT_CONTAINS(errorOf([] { loadCore("[imu]\ngyro_bias_prior = 0 0\n"); }),
                  "[imu] gyro_bias_prior: expected 3 numbers separated by blanks, got 2");
  EXPECT_CONTAINS(errorOf([] { loadCore("[start]\ndetect_rest = maybe\n"); }),
                  "[start] detect_rest: 'maybe' is not a boolean (true/false)");
  EXPECT_CONTAINS(
      errorOf([] { loadCore("[paper_gravity]\nformulation = numeric\n"); }),
      "[paper_gravity] formulation: 'numeric' is not one of 'integrated', 'differentiated'");
  // Given under a former name: both names, the line of the one given.
  EXPECT_CONTAINS(errorOf([] { loadCore("[bootstrap]\npoints = ten\n"); }),
                  "t.ini:2: [paper_bootstrap] points (given as [bootstrap] points): 'ten' is not "
                  "a number");
  EXPECT_CONTAINS(errorOf([] { loadCore("[static_detector]\n\nenabled = maybe\n"); }),
                  "t.ini:3: [start] detect_rest (given as [static_detector] enabled): 'maybe' is "
                  "not a boolean (true/false)");
}

// Values off by orders of magnitude are refused on load with the accepted range, instead of
// running for 22 s into NaN (a prior of 1e300) or failing later with a misleading status.
TEST(FreeInitConfigIni, AbsurdValuesAreRefusedWithTheAcceptedRange) {
  EXPECT_CONTAINS(errorOf([] { loadCore("[imu]\ngyro_bias_sigma0 = 1e300\n"); }),
                  "t.ini:2: [imu] gyro_bias_sigma0: 1e300 is out of range: accepted "
                  "[1e-06, 1] rad/s");
  EXPECT_CONTAINS(errorOf([] { loadCore("[doppler]\ndoppler_sigma = 30\n"); }),
                  "[doppler] doppler_sigma: 30 is out of range: accepted [1e-04, 1] m/s");
  EXPECT_CONTAINS(errorOf([] { loadCore("[doppler]\ndoppler_sigma = 1e999\n"); }),
                  "[doppler] doppler_sigma: '1e999' is out of the range of a double");
  EXPECT_CONTAINS(errorOf([] { loadCore("[window]\nduration = -1\n"); }),
                  "[window] duration: -1 is out of range: accepted [0.05, 60] s");
  EXPECT_CONTAINS(errorOf([] { loadCore("[doppler]\nmin_range = 5\nmax_range = 4\n"); }),
                  "t.ini:3: [doppler] max_range: must exceed min_range (5 m)");
  EXPECT_CONTAINS(
      errorOf([] {
        loadCore("[paper_gravity]\nuse_body_equation = false\nuse_lidar_equation = no\n");
      }),
      "t.ini:2: [paper_gravity] use_body_equation: at least one of the body and LiDAR "
      "equations");
  // Across the two layouts: the former name of one key, the current one of the other.
  EXPECT_CONTAINS(
      errorOf([] { loadCore("[velocimeter]\nmin_range = 5\n[doppler]\nmax_range = 4\n"); }),
      "t.ini:4: [doppler] max_range: must exceed min_range (5 m)");
  // The same ranges hold for a configuration filled in code.
  FreeInitConfig c;
  c.imu.gyro_bias_sigma0 = 1e300;
  EXPECT_CONTAINS(errorOf([&] { c.validate(); }),
                  "configuration key imu.gyro_bias_sigma0: 1e+300 is out of range");
}

TEST(FreeInitConfigIni, TheWindowKeysInSamplesAreGoneWithAPointerToTheirReplacement) {
  EXPECT_CONTAINS(errorOf([] { loadCore("[window]\nimu_samples = 100\n"); }),
                  "t.ini:2: [window] imu_samples: no longer a key: the window is given in "
                  "seconds, [window] duration");
  EXPECT_CONTAINS(errorOf([] { loadCore("[window]\nseed_imu_samples = 60\n"); }),
                  "[window] seed_imu_samples: no longer a key: the seed passes are given in "
                  "seconds, [paper_passes] seed_duration");
}

// An INI written for the earlier layout (sections named after the paper's stages) still loads:
// each key given under its former name is read as its current one, with one notice line naming
// both; the echo has the current names.
TEST(FreeInitConfigFormerNames, AreReadWithOneNoticePerKey) {
  std::vector<std::string> notices;
  const FreeInitConfig c = loadCore(
      "[velocimeter]\ndoppler_sigma = 0.05\ngyro_sigma = 0.004\n[window]\nduration = 0.6\n"
      "refinement_passes = 0\n[estimator]\nmethod = paper\nbootstrap_duration = 0.2\n"
      "[static_detector]\nenabled = false\n",
      &notices);
  EXPECT_EQ(c.doppler.doppler_sigma, 0.05);
  EXPECT_EQ(c.imu.gyro_sigma, 0.004);
  EXPECT_EQ(c.window.duration, 0.6);
  EXPECT_EQ(c.paper_passes.refinement_passes, 0);
  EXPECT_EQ(c.estimator.method, EstimatorParams::Method::Paper);
  EXPECT_EQ(c.start.duration, 0.2);
  EXPECT_FALSE(c.start.detect_rest);
  const std::vector<std::string> expected = {
      "t.ini:2: [velocimeter] doppler_sigma is now [doppler] doppler_sigma (the old name is read "
      "for now)",
      "t.ini:3: [velocimeter] gyro_sigma is now [imu] gyro_sigma (the old name is read for now)",
      "t.ini:6: [window] refinement_passes is now [paper_passes] refinement_passes (the old name "
      "is read for now)",
      "t.ini:9: [estimator] bootstrap_duration is now [start] duration (the old name is read for "
      "now)",
      "t.ini:11: [static_detector] enabled is now [start] detect_rest (the old name is read for "
      "now)"};
  EXPECT_EQ(notices, expected);
  // Without a list for them, the notices go to std::cerr.
  std::ostringstream err;
  std::streambuf* const cerr = std::cerr.rdbuf(err.rdbuf());
  FreeInitConfig d;
  d.load(IniFile::parse("[gravity]\naccel_sigma = 0.03\n", "u.ini"));
  std::cerr.rdbuf(cerr);
  EXPECT_EQ(err.str(),
            "u.ini:2: [gravity] accel_sigma is now [imu] accel_sigma (the old name is read for "
            "now)\n");
  EXPECT_EQ(d.imu.accel_sigma, 0.03);
}

// A key given under its former and its current name (or two former ones) is an error naming
// both, whatever their order; so is an unknown key in a former section.
TEST(FreeInitConfigFormerNames, AKeyGivenUnderTwoNamesIsAnError) {
  EXPECT_EQ(errorOf([] {
              loadCore("[velocimeter]\ndoppler_sigma = 0.05\n[doppler]\ndoppler_sigma = 0.06\n");
            }),
            "t.ini:2: [velocimeter] doppler_sigma: is now [doppler] doppler_sigma, also given "
            "(line 4): give it once");
  EXPECT_EQ(
      errorOf([] { loadCore("[start]\ndetect_rest = true\n[static_detector]\nenabled = true\n"); }),
      "t.ini:4: [static_detector] enabled: is now [start] detect_rest, also given (line "
      "2): give it once");
  EXPECT_EQ(
      errorOf([] { loadCore("[estimator]\nmax_iterations = 5\n[joint]\nmax_iterations = 6\n"); }),
      "t.ini:2: [estimator] max_iterations: is now [joint] max_iterations, also given "
      "(line 4): give it once");
  // [gravity] max_iterations (the Ceres solve's) and [estimator] max_iterations (the
  // smoother's) are two keys.
  const FreeInitConfig c =
      loadCore("[estimator]\nmax_iterations = 5\n[gravity]\nmax_iterations = 40\n");
  EXPECT_EQ(c.joint.max_iterations, 5);
  EXPECT_EQ(c.paper_gravity.max_iterations, 40);
  // Two former names of one key.
  const auto renames = std::vector<config::KeyRename>{{"a", "x", "c", "x"}, {"b", "y", "c", "x"}};
  std::vector<std::string> notices;
  EXPECT_EQ(errorOf([&] {
              IniFile::parse("[a]\nx = 1\n[b]\ny = 2\n", "r.ini")
                  .withRenames(renames, {"a", "b"}, notices);
            }),
            "r.ini:4: [b] y: is now [c] x, also given as [a] x (line 2): give it once");
}

// Every key of the earlier layout maps to exactly one current key, which takes the same value:
// the earlier layout as it was, each key with a value other than its default.
TEST(FreeInitConfigFormerNames, EveryFormerKeyIsOneCurrentKeyWithTheSameValue) {
  struct Former {
    const char* section;
    const char* key;
    const char* value;
  };
  const std::vector<Former> former = {
      {"estimator", "method", "paper"},
      {"estimator", "bootstrap_duration", "0.2"},
      {"estimator", "bootstrap_points", "1234"},
      {"estimator", "initial_tilt_sigma", "0.3"},
      {"estimator", "max_iterations", "7"},
      {"estimator", "zero_rate_at_rest", "false"},
      {"estimator", "lever_arm_gyro_noise", "false"},
      {"estimator", "rest_velocity_sigma", "0.006"},
      {"estimator", "accel_bias_random_walk", "0.002"},
      {"estimator", "calibration_rotation_sigma_deg", "0.5"},
      {"estimator", "time_offset_sigma", "0.001"},
      {"estimator", "test_rotation_sigma_deg", "1"},
      {"estimator", "test_time_offset_sigma", "0.02"},
      {"velocimeter", "doppler_sigma", "0.04"},
      {"velocimeter", "gyro_sigma", "0.003"},
      {"velocimeter", "vel_random_walk", "11"},
      {"velocimeter", "omega_random_walk", "2"},
      {"velocimeter", "aided_vel_random_walk", "0.04"},
      {"velocimeter", "gyro_bias_random_walk", "2e-4"},
      {"velocimeter", "gyro_bias_tau", "500"},
      {"velocimeter", "gyro_bias_sigma0", "0.02"},
      {"velocimeter", "gyro_bias_prior", "0.001 -0.002 0.003"},
      {"velocimeter", "kinematic_propagation", "false"},
      {"velocimeter", "doppler_updates_omega", "true"},
      {"velocimeter", "min_range", "2"},
      {"velocimeter", "max_range", "100"},
      {"velocimeter", "point_stride", "2"},
      {"velocimeter", "max_point_rate", "1e6"},
      {"velocimeter", "gate_sigma", "5"},
      {"velocimeter", "gate_min", "0.2"},
      {"velocimeter", "gate_rel", "0.02"},
      {"velocimeter", "doppler_ego_compensated", "true"},
      {"bootstrap", "points", "5000"},
      {"bootstrap", "iterations", "11"},
      {"bootstrap", "cauchy_scale", "0.2"},
      {"bootstrap", "prior_sigma", "30"},
      {"bootstrap", "min_info_eigen", "50"},
      {"static_detector", "enabled", "false"},
      {"static_detector", "max_speed", "0.06"},
      {"static_detector", "max_gyro_dev", "0.04"},
      {"static_detector", "zupt_sigma", "0.003"},
      {"static_detector", "check_period", "0.03"},
      {"window", "duration", "0.6"},
      {"window", "refinement_passes", "2"},
      {"window", "seed_pass_stride", "4"},
      {"window", "seed_duration", "0.2"},
      {"gravity", "formulation", "differentiated"},
      {"gravity", "use_body_equation", "false"},
      {"gravity", "use_lidar_equation", "false"},
      {"gravity", "accel_sigma", "0.03"},
      {"gravity", "accel_bias_bound", "0.6"},
      {"gravity", "accel_bias_prior_sigma", "0.2"},
      {"gravity", "lowpass_cutoff_hz", "5"},
      {"gravity", "velocity_error_correlation_time", "0.1"},
      {"gravity", "equations_share_errors", "false"},
      {"gravity", "estimate_gyro_bias", "false"},
      {"gravity", "loss_scale", "2"},
      {"gravity", "max_iterations", "40"},
  };
  // The current key of each former one: declared as its former name, or the same name in a
  // section that still has it.
  const auto renames = config::formerNames(FreeInitConfig::sections());
  std::size_t unchanged = 0;
  for (const Former& f : former) {
    SCOPED_TRACE(std::string(f.section) + "." + f.key);
    std::vector<std::pair<std::string, std::string>> current;
    for (const config::KeyRename& r : renames)
      if (r.from_section == f.section && r.from_key == f.key)
        current.push_back({r.to_section, r.to_key});
    for (const config::SectionBase* s : FreeInitConfig::sections())
      for (const config::KeyInfo& k : s->keys())
        if (s->name() == f.section && k.name == f.key) current.push_back({s->name(), k.name});
    ASSERT_EQ(current.size(), 1u);
    unchanged += current[0] == std::make_pair(std::string(f.section), std::string(f.key)) ? 1 : 0;
    std::vector<std::string> notices;
    const FreeInitConfig old =
        loadCore("[" + std::string(f.section) + "]\n" + f.key + " = " + f.value + "\n", &notices);
    EXPECT_EQ(notices.size(),
              current[0].first == f.section && current[0].second == f.key ? 0u : 1u);
    const FreeInitConfig now =
        loadCore("[" + current[0].first + "]\n" + current[0].second + " = " + f.value + "\n");
    EXPECT_EQ(dumpOf(old), dumpOf(now));
    EXPECT_NE(dumpOf(now), dumpOf(FreeInitConfig{}));  // the value was taken
  }
  EXPECT_EQ(unchanged, 2u);  // [estimator] method, [window] duration
  // No former name is declared that the earlier layout did not have.
  for (const config::KeyRename& r : renames) {
    const bool known = std::any_of(former.begin(), former.end(), [&](const Former& f) {
      return r.from_section == f.section && r.from_key == f.key;
    });
    EXPECT_TRUE(known) << r.from_section << "." << r.from_key;
  }
  EXPECT_EQ(renames.size(), former.size() - unchanged);
  EXPECT_EQ(FreeInitConfig::formerSectionNames(),
            (std::vector<std::string>{"velocimeter", "gravity", "bootstrap", "static_detector"}));
}

// The echo of a configuration loads back to the same configuration: every key of every section
// changed from its default, dumped, loaded and dumped again.
TEST(FreeInitConfigIni, EffectiveConfigEchoLoadsBackToTheSameConfig) {
  FreeInitConfig c;
  c.doppler.doppler_sigma = 0.0123456789012345;
  c.imu.gyro_bias_prior = Vec3(1e-3, -2.5e-4, 1.0 / 3.0 * 1e-2);
  c.paper_velocimeter.kinematic_propagation = false;
  c.doppler.point_stride = 7;
  c.paper_bootstrap.points = 1234;
  c.start.detect_rest = false;
  c.window.duration = 0.75;
  c.paper_passes.seed_duration = 0;
  c.paper_gravity.formulation = GravityFormulation::Differentiated;
  c.paper_gravity.loss_scale = 2.0 / 3.0;
  std::ostringstream a;
  c.dump(a);
  std::vector<std::string> notices;
  const FreeInitConfig d = loadCore(a.str(), &notices);
  EXPECT_TRUE(notices.empty()) << notices.front();  // the echo has the current names only
  std::ostringstream b;
  d.dump(b);
  EXPECT_EQ(a.str(), b.str());
  EXPECT_EQ(d.doppler.doppler_sigma, c.doppler.doppler_sigma);  // exact: shortest digits
  EXPECT_EQ(d.imu.gyro_bias_prior, c.imu.gyro_bias_prior);
  EXPECT_EQ(d.paper_gravity.loss_scale, c.paper_gravity.loss_scale);
  EXPECT_EQ(d.paper_gravity.formulation, GravityFormulation::Differentiated);
  EXPECT_EQ(d.window.duration, 0.75);
  EXPECT_FALSE(d.start.detect_rest);
  // Each default differs from the value above, so every line was loaded, not defaulted.
  std::ostringstream defaults;
  FreeInitConfig().dump(defaults);
  EXPECT_NE(defaults.str(), a.str());
}

// The declared keys carry their unit, doc, default (the struct's own), accepted values and what
// reads them; a section named for one estimator has only keys that estimator reads.
TEST(FreeInitConfigIni, DeclarationsDocumentEveryKey) {
  std::size_t n = 0;
  for (const config::SectionBase* s : FreeInitConfig::sections()) {
    for (const config::KeyInfo& k : s->keys()) {
      EXPECT_FALSE(k.unit.empty()) << s->name() << "." << k.name;
      EXPECT_FALSE(k.doc.empty()) << s->name() << "." << k.name;
      EXPECT_FALSE(k.default_value.empty()) << s->name() << "." << k.name;
      EXPECT_FALSE(k.readers.empty()) << s->name() << "." << k.name;
      if (s->name().rfind("paper_", 0) == 0) {
        EXPECT_EQ(k.readers.rfind("paper", 0), 0u) << s->name() << "." << k.name;
      }
      if (s->name() == "joint") {
        EXPECT_EQ(k.readers, "joint") << k.name;
      }
      ++n;
    }
  }
  EXPECT_EQ(n, 64u);
  // The readers are shown in the echo: after each key's doc, and per section.
  const std::string dump = dumpOf(FreeInitConfig{});
  EXPECT_CONTAINS(dump, "[imu]\n; the IMU's noise and bias model");
  EXPECT_CONTAINS(dump, "; read by: joint, paper, odometry, input checks\n");
  EXPECT_CONTAINS(dump, "; [-] smoother iterations, at most (accepted: [1, 100]) (joint)\n");
  EXPECT_CONTAINS(dump,
                  "; [bool] use a start at rest (joint: zero velocity and rate while the IMU "
                  "shows rest; paper: zero-velocity mode) (joint, paper)\n");
  const auto w = windowSection().keys();
  EXPECT_EQ(w[0].name, "duration");
  EXPECT_EQ(w[0].unit, "s");
  EXPECT_EQ(w[0].default_value, "0.5");
  EXPECT_EQ(w[0].accepted, "[0.05, 60]");
}

// The window rule: the samples with t - t_0 < duration; rounding of absolute stamps does not
// move the end by a sample.
TEST(WindowRule, HalfASecondIsTheSameSpanAtAnyImuRate) {
  for (const double rate : {200.0, 400.0, 1000.0}) {
    std::vector<ImuSample> imu(2000);
    for (std::size_t k = 0; k < imu.size(); ++k)
      imu[k].t = 1700000000.123 + static_cast<double>(k) / rate;  // stamps rounded at 2.4e-7 s
    for (const std::size_t first : {0u, 17u, 333u}) {
      const auto last = windowLastSample(imu, first, 0.5);
      ASSERT_TRUE(last) << rate;
      EXPECT_EQ(*last - first + 1, static_cast<std::size_t>(0.5 * rate)) << rate;
    }
  }
  // A recording that ends before the window closes does not cover it.
  std::vector<ImuSample> shortrec(99);
  for (std::size_t k = 0; k < shortrec.size(); ++k) shortrec[k].t = 0.005 * static_cast<double>(k);
  EXPECT_FALSE(windowLastSample(shortrec, 0, 0.5));
  shortrec.push_back({0.495, Vec3::Zero(), Vec3::Zero()});  // the 100th closes it
  EXPECT_EQ(windowLastSample(shortrec, 0, 0.5), std::optional<std::size_t>(99));
}

TEST(WindowRule, AGapBeyondTheEndClosesTheWindowOnTheSampleBefore) {
  // 200 Hz, then nothing between 0.40 s and 0.60 s.
  std::vector<ImuSample> imu;
  for (int k = 0; k <= 80; ++k) imu.push_back({0.005 * k, Vec3::Zero(), Vec3::Zero()});
  for (int k = 120; k <= 200; ++k) imu.push_back({0.005 * k, Vec3::Zero(), Vec3::Zero()});
  EXPECT_EQ(windowLastSample(imu, 0, 0.5), std::optional<std::size_t>(80));
  EXPECT_EQ(windowSample(0, 0.4, 0.6, 0.5), WindowSample::Outside);
  EXPECT_EQ(windowSample(0, 0.49, 0.495, 0.5), WindowSample::Last);
  EXPECT_EQ(windowSample(0, 0.485, 0.49, 0.5), WindowSample::Inside);
  EXPECT_EQ(windowSample(0, 0, 0, 0.5), WindowSample::Inside);  // the first sample
}

// The estimator's window is 0.5 s whatever the IMU rate (a 1 kHz IMU used to get 0.1 s from the
// 100-sample window): from the trajectory's first sample to the state, 99 and 499 sample
// intervals; its nodes at every sample at 200 Hz, at every fifth and the window's last at 1 kHz
// ([joint] node_rate = 200).
TEST(WindowRule, TheEstimatorsWindowIsInSeconds) {
  for (const double rate : {200.0, 1000.0}) {
    sim::ScenarioConfig sc = sim::preset("dyna_01", 1);
    sc.duration = 0.7;
    sc.points_per_frame = 4000;
    sc.imu_rate = rate;
    const sim::Recording rec = sim::simulate(sc);
    FreeInitConfig cfg;
    cfg.extrinsics = rec.extrinsics;
    const InitResult r = FreeInit::run(cfg, rec.imu, rec.frames);
    ASSERT_TRUE(r.state.ok()) << r.state.message;
    ASSERT_FALSE(r.trajectory.empty());
    const std::size_t samples = static_cast<std::size_t>(0.5 * rate),
                      stride = static_cast<std::size_t>(rate / 200.0);
    EXPECT_EQ(r.trajectory.size(), (samples - 1 + stride - 1) / stride + 1) << rate;
    EXPECT_NEAR(r.state.timestamp - r.trajectory.front().t, 0.5 - 1.0 / rate, 1e-6) << rate;
  }
}

// A list of values as numbered keys (items()) and keys dumped only when they matter (when()): the
// element keys apply after the length whatever their order, an element beyond the length or one
// the length adds but the file leaves out is named, and the dump reads back to the same struct.
namespace {
struct Shelf {
  std::string kind = "plain";
  double tilt = 0;  ///< only for kind = tilted
  std::vector<double> widths = {1.0};
};
const config::Section<Shelf>& shelfSection() {
  using V = std::vector<double>;
  static const auto s =
      config::Section<Shelf>("shelf")
          .choice("kind", &Shelf::kind, {{"plain", "plain"}, {"tilted", "tilted"}}, "shape")
          .number("tilt", &Shelf::tilt, "deg", config::between(-45, 45), "tilt of a tilted shelf")
          .when([](const Shelf& x) { return x.kind == "tilted"; })
          .custom("boards", &Shelf::widths, "-", "[0, 10]",
                  std::function<std::string(std::string_view, V&)>([](std::string_view t, V& v) {
                    long double n = 0;
                    std::string err = config::parseInteger(t, 0, 10, n);
                    if (err.empty()) v.resize(static_cast<std::size_t>(n));
                    return err;
                  }),
                  std::function<std::string(const V&)>(
                      [](const V& v) { return std::to_string(v.size()); }),
                  "number of boards")
          .items("board_", &Shelf::widths, "boards", "m", "> 0",
                 std::function<std::string(std::string_view, double&)>(
                     [](std::string_view t, double& x) { return config::parseNumber(t, x); }),
                 std::function<std::string(const double&)>(config::formatNumber),
                 std::function<std::string(const double&)>(
                     [](const double& x) { return x > 0 ? "" : "must be > 0"; }),
                 "width of board k");
  return s;
}
}  // namespace

TEST(ConfigSection, ItemsAndKeysDumpedOnlyWhenTheyMatter) {
  Shelf s;
  shelfSection().load(
      IniFile::parse("[shelf]\nboard_2 = 0.5\nboards = 3\nboard_3 = 0.25\nboard_1 = 2\n", "a.ini"),
      s);
  EXPECT_EQ(s.widths, (std::vector<double>{2, 0.5, 0.25}));
  std::ostringstream out;
  shelfSection().dump(s, out);
  EXPECT_EQ(out.str().find("\ntilt "), std::string::npos) << out.str();
  EXPECT_NE(out.str().find("board_3                         = 0.25"), std::string::npos)
      << out.str();
  Shelf back;
  shelfSection().load(IniFile::parse(out.str(), "dump.ini"), back);
  EXPECT_EQ(back.widths, s.widths);
  s.kind = "tilted";
  s.tilt = 3;
  std::ostringstream tilted;
  shelfSection().dump(s, tilted);
  EXPECT_NE(tilted.str().find("\ntilt "), std::string::npos) << tilted.str();
  // Only the length's new elements must be given (board_1 keeps the struct's value).
  Shelf two;
  shelfSection().load(IniFile::parse("[shelf]\nboards = 2\nboard_2 = 3\n", "b.ini"), two);
  EXPECT_EQ(two.widths, (std::vector<double>{1, 3}));

  EXPECT_EQ(errorOf([] {
              Shelf x;
              shelfSection().load(IniFile::parse("[shelf]\nboard_2 = 1\n", "c.ini"), x);
            }),
            "c.ini:2: [shelf] board_2: beyond boards = 1");
  EXPECT_EQ(errorOf([] {
              Shelf x;
              shelfSection().load(IniFile::parse("[shelf]\nboards = 3\nboard_2 = 1\n", "d.ini"), x);
            }),
            "d.ini:1: [shelf] board_3: missing (boards = 3)");
  EXPECT_EQ(errorOf([] {
              Shelf x;
              shelfSection().load(IniFile::parse("[shelf]\nboard_1 = -1\n", "e.ini"), x);
            }),
            "e.ini:2: [shelf] board_1: must be > 0");
  EXPECT_EQ(errorOf([] {
              Shelf x;
              x.widths = {1, 0};
              shelfSection().validate(x);
            }),
            "configuration key shelf.board_2: must be > 0");
  const auto keys = shelfSection().keys();
  ASSERT_EQ(keys.size(), 4u);
  EXPECT_EQ(keys[3].name, "board_<k>");
  EXPECT_EQ(keys[3].default_value, "");
}

// The three number forms (io/number_format.h): the shortest exact text reads back to the same
// double; significant digits and decimals print as printf's %.*g and %.*f.
TEST(NumberFormat, ShortestSignificantAndFixed) {
  for (const double x : {0.0, -0.0, 0.1, 1.0 / 3.0, -2.5e-9, 123456789.0, 6.02214076e23, 9.81}) {
    EXPECT_EQ(std::stod(formatNumber(x)), x) << formatNumber(x);
    for (const int n : {1, 2, 3, 4, 6, 9, 12}) {
      char g[64], f[512];
      std::snprintf(g, sizeof g, "%.*g", n, x);
      std::snprintf(f, sizeof f, "%.*f", n, x);
      EXPECT_EQ(formatSignificant(x, n), g) << x << " " << n;
      EXPECT_EQ(formatFixed(x, n), f) << x << " " << n;
    }
  }
  EXPECT_EQ(formatNumber(0.1), "0.1");
  EXPECT_EQ(formatSignificant(0.012345, 3), "0.0123");
  EXPECT_EQ(formatFixed(1.5, 3), "1.500");
}
