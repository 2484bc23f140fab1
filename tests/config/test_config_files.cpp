// Every INI section the apps read, through its declaration: the app's sections, [extrinsics],
// the bag importer's, icp-slam's [freeinit_scan], the rawlog-grabber driver's; and the shipped
// ini/*.ini files: each documents every key of the sections it has, its values load, and where
// it shows a default (a line ";key = value") that default is the code's.
#include <freeinit/app_support/app_config.h>
#include <freeinit/app_support/icp_slam_bridge.h>
#include <freeinit/io/config_section.h>
#include <freeinit/io/ini_file.h>
#include <freeinit/mrpt_plugins/doppler_lidar_imu_udp.h>
#include <gtest/gtest.h>
#include <mrpt/config/CConfigFile.h>
#include <mrpt/config/CConfigFileMemory.h>
#ifdef FREEINIT_WITH_BAG_IMPORT
#include "bag_import_app.h"
#endif

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <regex>
#include <set>
#include <sstream>

using namespace freeinit;
using namespace freeinit::mrpt_plugins;
using namespace freeinit::app_support;
using namespace freeinit::apps;
using config::ConfigError;
namespace fs = std::filesystem;

namespace {

const std::string kSrc = FREEINIT_SOURCE_DIR;

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

std::string tmpFile(const std::string& name, const std::string& text) {
  const fs::path d = fs::temp_directory_path() / "freeinit_test_config_files";
  fs::create_directories(d);
  const std::string p = (d / name).string();
  std::ofstream(p) << text;
  return p;
}

AppConfig app(const std::string& text) { return loadAppConfigFromText(text, "a.ini"); }

std::string dump(const AppConfig& c) {
  std::ostringstream os;
  dumpAppConfig(c, os);
  return os.str();
}

// The driver's own loading (CGenericSensor::loadConfig rethrows its errors as MRPT exceptions,
// which reformat the message and add a call stack).
struct Driver : CDopplerLidarImuUdp {
  using CDopplerLidarImuUdp::loadConfig_sensorSpecific;
};

}  // namespace

// ---------------------------------------------------------------------------------------------
// The app's configuration.

TEST(AppConfigIni, MisspeltSectionsDuplicatedKeysAndVariablesAreErrors) {
  EXPECT_CONTAINS(errorOf([] { app("[velocimetr]\ndoppler_sigma = 0.1\n"); }),
                  "a.ini:1: [velocimetr]: unknown section (did you mean [velocimeter]?)");
  // [bag_import] is read too (a ROS recording given as the input).
  EXPECT_EQ(app("[bag_import]\nimu_topic = /imu\n").bag_import.bag.imu_topic, "/imu");
  EXPECT_CONTAINS(errorOf([] { app("[output]\nply = false\nply = true\n"); }),
                  "a.ini:3: [output] ply: key given twice (first at line 2)");
  // The fuzzer's reproducer, which escaped as an MRPT exception with a call stack.
  EXPECT_CONTAINS(errorOf([] { app("[input]\nimu_label = ${FOO\n"); }),
                  "a.ini:2: [input] imu_label: '${FOO': variables and expressions");
  EXPECT_CONTAINS(errorOf([] { app("[output]\nsnapshot_width = 10\n"); }),
                  "a.ini:2: [output] snapshot_width: 10 is out of range: accepted [64, 16384] px");
  EXPECT_CONTAINS(errorOf([] { app("[input]\nmin_imu_rate = 0\n"); }),
                  "[input] min_imu_rate: 0 is out of range: accepted [1, 1e+05] Hz");
  EXPECT_CONTAINS(errorOf([] { loadAppConfig(kSrc + "/rawlogs/stat_01.rawlog"); }),
                  "stat_01.rawlog:1: binary data");
}

// The extrinsics come from the observations' sensorPose unless the INI says otherwise, and the
// INI's own extrinsics are used only when asked for: never both, never neither.
TEST(AppConfigIni, ExtrinsicsFromSensorPoseByDefaultOrExplicitlyFromTheIni) {
  const AppConfig none = app("");
  EXPECT_TRUE(none.extrinsics.from_sensor_pose);
  EXPECT_FALSE(none.extrinsics.given_in_ini);
  EXPECT_TRUE(AppConfig{}.extrinsics.from_sensor_pose);

  EXPECT_CONTAINS(errorOf([] { app("[extrinsics]\nR_bl = 1 0 0 0 1 0 0 0 1\np_bl = 0 0 0.1\n"); }),
                  "a.ini:2: [extrinsics] R_bl: given, but from_sensor_pose is true (the default");
  EXPECT_CONTAINS(errorOf([] { app("[extrinsics]\nfrom_sensor_pose = true\np_bl = 0 0 0.1\n"); }),
                  "a.ini:3: [extrinsics] p_bl: given, but from_sensor_pose = true: choose one");
  EXPECT_CONTAINS(errorOf([] { app("[extrinsics]\nfrom_sensor_pose = false\n"); }),
                  "a.ini:2: [extrinsics] from_sensor_pose: false, but no extrinsics are given");
  EXPECT_CONTAINS(
      errorOf([] { app("[extrinsics]\nfrom_sensor_pose = false\nR_bl = 1 0 0 0 1 0 0 0 2\n"); }),
      "a.ini:3: [extrinsics] R_bl: not a rotation matrix");
  EXPECT_CONTAINS(errorOf([] {
                    app("[extrinsics]\nfrom_sensor_pose = false\nR_bl = 1 0 0 0 1 0 0 0 1\n"
                        "yaw_deg = 3\n");
                  }),
                  "[extrinsics] R_bl: give either R_bl or roll_deg/pitch_deg/yaw_deg, not both");

  const AppConfig c =
      app("[extrinsics]\nfrom_sensor_pose = false\nroll_deg = 2\npitch_deg = -3\nyaw_deg = 90\n"
          "p_bl = 0.1 0.2 0.3\n");
  EXPECT_FALSE(c.extrinsics.from_sensor_pose);
  EXPECT_TRUE(c.extrinsics.given_in_ini);
  const double d = M_PI / 180;
  const Mat3 R =
      (Eigen::AngleAxisd(90 * d, Vec3::UnitZ()) * Eigen::AngleAxisd(-3 * d, Vec3::UnitY()) *
       Eigen::AngleAxisd(2 * d, Vec3::UnitX()))
          .toRotationMatrix();
  EXPECT_LT((c.core.extrinsics.R_bl - R).norm(), 1e-15);
  EXPECT_EQ(c.core.extrinsics.p_bl, Vec3(0.1, 0.2, 0.3));
}

// The effective-configuration echo loads back to the same configuration, with the extrinsics
// either way.
TEST(AppConfigIni, EffectiveConfigEchoLoadsBackToTheSameConfig) {
  AppConfig c;
  c.core.doppler.doppler_sigma = 0.047;
  c.core.window.duration = 0.4;
  c.core.paper_gravity.formulation = GravityFormulation::Differentiated;
  c.input.imu_label = "xsens imu";
  c.input.lidar_label = "";
  c.input.min_imu_rate = 123.5;
  c.output.ply = false;
  c.output.snapshot_height = 601;
  for (const bool from_pose : {true, false}) {
    c.extrinsics.from_sensor_pose = from_pose;
    c.core.extrinsics.R_bl =
        Eigen::AngleAxisd(0.3, Vec3(1, -2, 0.5).normalized()).toRotationMatrix();
    c.core.extrinsics.p_bl = Vec3(0.017, -0.002, -0.052);
    if (from_pose) c.core.extrinsics = Extrinsics{};  // taken from the rawlog, not the INI
    const std::string echo = dump(c);
    const AppConfig d = loadAppConfigFromText(echo, "effective_config.ini");
    EXPECT_EQ(dump(d), echo);
    EXPECT_EQ(d.extrinsics.from_sensor_pose, from_pose);
    EXPECT_EQ(d.core.extrinsics.R_bl, c.core.extrinsics.R_bl);  // shortest exact digits
    EXPECT_EQ(d.core.extrinsics.p_bl, c.core.extrinsics.p_bl);
    EXPECT_EQ(d.input.imu_label, "xsens imu");
    EXPECT_EQ(d.input.lidar_label, "");
    EXPECT_EQ(d.core.doppler.doppler_sigma, 0.047);
    EXPECT_EQ(d.core.window.duration, 0.4);
    EXPECT_EQ(d.output.snapshot_height, 601);
  }
}

// ---------------------------------------------------------------------------------------------
// The other programs' sections.

TEST(ScanSliceIni, OnlyItsSectionIsReadAndItIsStrict) {
  const std::string ok =
      tmpFile("slice.ini",
              "[freeinit_scan]\nz_min = -1\nbins = 181\n[ICP]\nthresholdDist = 0.5 // MRPT's\n");
  const ScanSliceParams p = loadScanSliceParams(ok);
  EXPECT_EQ(p.z_min, -1);
  EXPECT_EQ(p.bins, 181);
  const std::string typo = tmpFile("slice_typo.ini", "[freeinit_scan]\nzmin = -1\n");
  EXPECT_CONTAINS(errorOf([&] { loadScanSliceParams(typo); }),
                  "slice_typo.ini:2: [freeinit_scan] zmin: unknown key (did you mean z_min?)");
  const std::string bad = tmpFile("slice_bad.ini", "[freeinit_scan]\nz_min = 2\nz_max = 1\n");
  EXPECT_CONTAINS(errorOf([&] { loadScanSliceParams(bad); }),
                  "slice_bad.ini:3: [freeinit_scan] z_max: must be greater than z_min");
}

// The rawlog-grabber driver's section rejects unknown keys, accepts rawlog-grabber's own.
TEST(GrabberDriverIni, UnknownKeysAreRefusedRawlogGrabbersOwnAccepted) {
  mrpt::config::CConfigFileMemory cfg;
  cfg.setContent(
      "[LIVE]\ndriver = CDopplerLidarImuUdp\nprocess_rate = 200\nmax_queue_len = 100\n"
      "grab_decimation = 1\nsensorLabel = L\npose_x = 0\npose_yaw = 0\nport = 0\n");
  {
    CDopplerLidarImuUdp sensor;
    EXPECT_NO_THROW(sensor.loadConfig(cfg, "LIVE"));
  }
  cfg.write("LIVE", "prot", 47801);
  Driver sensor;
  EXPECT_CONTAINS(errorOf([&] { sensor.loadConfig_sensorSpecific(cfg, "LIVE"); }),
                  "rawlog-grabber configuration: [LIVE] prot: unknown key (did you mean port?)");
  // From a file (rawlog-grabber's CConfigFile): lines and duplicated keys are known.
  const std::string f = tmpFile("grab.ini",
                                "[global]\nx = 1\n[S]\ndriver = CDopplerLidarImuUdp\n"
                                "port = 1\nframe_timeout_ms = 100\nport = 2\n");
  mrpt::config::CConfigFile file(f);
  Driver from_file;
  EXPECT_CONTAINS(errorOf([&] { from_file.loadConfig_sensorSpecific(file, "S"); }),
                  "grab.ini:7: [S] port: key given twice (first at line 5)");
}

TEST(GrabberDriverIni, MillisecondKeysAreConvertedOnceAndRangesHold) {
  const auto ini = config::IniFile::parse(
      "[S]\nframe_timeout_ms = 250\nreorder_timeout_ms = 0\nport = 47999\n", "g.ini");
  UdpDriverParams p;
  udpDriverSection().load(ini, "S", p);
  EXPECT_DOUBLE_EQ(p.source.receiver.frame_timeout, 0.25);
  EXPECT_EQ(p.source.receiver.reorder_timeout, 0.0);
  EXPECT_EQ(p.source.port, 47999);
  std::ostringstream os;
  udpDriverSection().dump(p, os);
  EXPECT_CONTAINS(os.str(), "frame_timeout_ms");
  EXPECT_CONTAINS(os.str(), "= 250 ");
  const auto bad = config::IniFile::parse("[S]\nport = 70000\nframe_timeout_ms = 0\n", "g.ini");
  EXPECT_CONTAINS(errorOf([&] { udpDriverSection().load(bad, "S", p); }),
                  "g.ini:2: [S] port: 70000 is out of range: accepted [0, 65535]");
}

#ifdef FREEINIT_WITH_BAG_IMPORT
TEST(BagImportIni, ExtrinsicsAreOptionalAndOtherSectionsRefused) {
  const std::string ext = "[extrinsics]\nR_bl = 1 0 0 0 1 0 0 0 1\np_bl = 0 0 0\n";
  // Without them, the recording's /tf_static must give them (checked when importing).
  EXPECT_FALSE(loadBagImportSettings(tmpFile("b1.ini", "[bag_import]\n")).extrinsics_given);
  EXPECT_TRUE(loadBagImportSettings(tmpFile("b1e.ini", ext)).extrinsics_given);
  EXPECT_CONTAINS(errorOf([&] {
                    loadBagImportSettings(
                        tmpFile("b2.ini", "[bag_import]\n[extrinsics]\nfrom_sensor_pose = true\n"));
                  }),
                  "b2.ini:3: [extrinsics] from_sensor_pose: a bag has no sensor poses");
  EXPECT_CONTAINS(
      errorOf([&] { loadBagImportSettings(tmpFile("b3.ini", ext + "[velocimeter]\n")); }),
      "b3.ini:4: [velocimeter]: unknown section");
  EXPECT_CONTAINS(
      errorOf([&] {
        loadBagImportSettings(tmpFile("b4.ini", "[bag_import]\ndoppler_sign = 2\n" + ext));
      }),
      "b4.ini:2: [bag_import] doppler_sign: '2' is not one of '1', '-1'");
  EXPECT_CONTAINS(
      errorOf([&] {
        loadBagImportSettings(tmpFile("b5.ini", "[bag_import]\ntime_scale = 0\n" + ext));
      }),
      "b5.ini:2: [bag_import] time_scale: 0 is out of range: accepted (0, 1000] s per unit");
  EXPECT_CONTAINS(
      errorOf([&] {
        loadBagImportSettings(tmpFile("b6.ini", "[bag_import]\nlidar_label = IMU\n" + ext));
      }),
      "b6.ini:2: [bag_import] lidar_label: must differ from imu_label");
  const auto s =
      loadBagImportSettings(tmpFile("b7.ini", "[bag_import]\nintensity_field =\n" + ext));
  EXPECT_EQ(s.bag.cloud.intensity.name, "");
}

// Clouds without a per-point time, scan stamps from a trigger topic or the bag time, clock offsets
// of days, and the optional [doppler_fit]: declared, range-checked and cross-checked.
TEST(BagImportIni, StampSourcesFrameDurationAndDopplerFit) {
  const std::string ext = "[extrinsics]\nR_bl = 1 0 0 0 1 0 0 0 1\np_bl = 0 0 0\n";
  auto load = [&](const std::string& name, const std::string& text) {
    return loadBagImportSettings(tmpFile(name, text + ext));
  };
  const auto radar = load("s1.ini",
                          "[bag_import]\ntime_field =\nframe_duration = 0.0185\n"
                          "stamp_source = bag_time\nlidar_time_offset = -338525.016\n"
                          "[doppler_fit]\nsigma_floor = 0.036\nmin_inlier_fraction = 0.6\n");
  EXPECT_EQ(radar.bag.cloud.time.field.name, "");
  EXPECT_EQ(radar.bag.cloud.time.frame_duration, 0.0185);
  EXPECT_EQ(radar.bag.stamp_source, ros1::StampSource::kBagTime);
  EXPECT_EQ(radar.bag.lidar_time_offset, -338525.016);
  EXPECT_EQ(radar.doppler_fit.sigma_floor, 0.036);
  EXPECT_EQ(radar.doppler_fit.min_inlier_fraction, 0.6);
  EXPECT_EQ(radar.doppler_fit.inlier_threshold, ros1::DopplerFitParams{}.inlier_threshold);
  EXPECT_CONTAINS(errorOf([&] { load("s2.ini", "[bag_import]\nstamp_source = gps\n"); }),
                  "s2.ini:2: [bag_import] stamp_source: 'gps' is not one of 'header', 'trigger', "
                  "'bag_time'");
  EXPECT_CONTAINS(
      errorOf([&] { load("s3.ini", "[bag_import]\ntime_field =\nframe_duration = 11\n"); }),
      "s3.ini:3: [bag_import] frame_duration: 11 is out of range: accepted [0, 10] s");
  EXPECT_CONTAINS(errorOf([&] { load("s4.ini", "[bag_import]\nframe_duration = 0.1\n"); }),
                  "s4.ini:2: [bag_import] frame_duration: is for clouds without a per-point time");
  EXPECT_CONTAINS(errorOf([&] { load("s5.ini", "[bag_import]\nstamp_source = trigger\n"); }),
                  "[bag_import] trigger_topic: is required with stamp_source = trigger");
  EXPECT_CONTAINS(errorOf([&] { load("s6.ini", "[bag_import]\ntrigger_topic = /t\n"); }),
                  "s6.ini:2: [bag_import] trigger_topic: is only read with stamp_source = trigger");
  EXPECT_CONTAINS(errorOf([&] { load("s7.ini", "[bag_import]\nlidar_time_offset = 5e9\n"); }),
                  "s7.ini:2: [bag_import] lidar_time_offset: 5e9 is out of range: accepted "
                  "[-4294967296, 4294967296] s");
  EXPECT_CONTAINS(
      errorOf([&] { load("s8.ini", "[doppler_fit]\nmin_inlier_fraction = 1.5\n"); }),
      "s8.ini:2: [doppler_fit] min_inlier_fraction: 1.5 is out of range: accepted [0, 1]");
  EXPECT_CONTAINS(errorOf([&] { load("s9.ini", "[doppler_fit]\ninlier_treshold = 0.1\n"); }),
                  "s9.ini:2: [doppler_fit] inlier_treshold: unknown key (did you mean "
                  "inlier_threshold?)");
  EXPECT_CONTAINS(errorOf([&] { load("s10.ini", "[doppler_fit]\ninlier_threshold = 0\n"); }),
                  "s10.ini:2: [doppler_fit] inlier_threshold: 0 is out of range: accepted "
                  "(0, 100] m/s");
}
#endif

// ---------------------------------------------------------------------------------------------
// The shipped INI files.
namespace {

struct ShippedIni {
  /// The declared sections the file may have, by name.
  std::vector<const config::SectionBase*> sections;
  /// Sections another program reads (MRPT's), not checked here.
  std::set<std::string> foreign;
  /// Every value in the file (set or commented out) claims to be the default.
  bool all_defaults = false;
  std::function<void(const std::string& path)> load;  ///< through the app's loader
};

std::map<std::string, ShippedIni> shippedIniFiles() {
  std::map<std::string, ShippedIni> m;
  m["freeinit.ini"] = {appSections(), {}, true, [](const std::string& p) {
                         // All defaults: the file loads to the code's default configuration.
                         EXPECT_EQ(dump(loadAppConfig(p)), dump(AppConfig{}));
                       }};
  m["freeinit_radar.ini"] = {
      appSections(), {}, false, [](const std::string& p) { loadAppConfig(p); }};
  m["icp_slam.ini"] = {{&scanSliceSection()},
                       {"MappingApplication", "MappingApplication_pointsMap_00_insertOpts", "ICP"},
                       false,
                       [](const std::string& p) { loadScanSliceParams(p); }};
  m["rawlog_grabber_doppler_udp.ini"] = {
      {&udpDriverSection()}, {"global"}, false, [](const std::string& p) {
        mrpt::config::CConfigFile cfg(p);
        CDopplerLidarImuUdp sensor;
        sensor.loadConfig(cfg, udpDriverSection().name());
      }};
#ifdef FREEINIT_WITH_BAG_IMPORT
  for (const char* f : {"import_bag.ini", "import_bag_vehicular.ini", "import_bag_ti_mmwave.ini"})
    m[f] = {{&bags::importSection(), &dopplerFitSection(), &extrinsicsPoseSection()},
            {},
            false,
            [](const std::string& p) { loadBagImportSettings(p); }};
#endif
  return m;
}

// "key = value" and ";key = value" lines by section (the value without its comment).
struct Documented {
  std::map<std::string, std::map<std::string, std::pair<std::string, bool>>> keys;  // commented?
  std::vector<std::string> sections;
};

Documented scan(const std::string& path) {
  Documented d;
  std::ifstream in(path);
  std::string line, section;
  const std::regex header(R"(^\s*\[([^\]]+)\].*)");
  const std::regex entry(R"(^(;?)([A-Za-z_][A-Za-z0-9_.-]*)\s*=\s*([^;#]*).*)");
  std::smatch m;
  while (std::getline(in, line)) {
    if (std::regex_match(line, m, header)) {
      section = m[1];
      d.sections.push_back(section);
    } else if (!section.empty() && std::regex_match(line, m, entry)) {
      std::string v = m[3];
      while (!v.empty() && std::isspace(static_cast<unsigned char>(v.back()))) v.pop_back();
      d.keys[section][m[2]] = {v, m[1] == ";"};
    }
  }
  return d;
}

}  // namespace

TEST(ShippedIniFiles, EachDocumentsEveryKeyOfItsSectionsWithTheCodesDefaultsAndLoads) {
  const auto table = shippedIniFiles();
  std::size_t files = 0;
  for (const auto& entry : fs::directory_iterator(kSrc + "/ini")) {
    const std::string name = entry.path().filename().string();
    if (entry.path().extension() != ".ini") continue;
    const auto it = table.find(name);
#ifndef FREEINIT_WITH_BAG_IMPORT
    if (name.rfind("import_bag", 0) == 0) continue;  // its loader is not built
#endif
    ASSERT_NE(it, table.end()) << "ini/" << name << " is not checked: add it to shippedIniFiles()";
    const ShippedIni& shipped = it->second;
    const Documented doc = scan(entry.path().string());
    for (const std::string& section : doc.sections) {
      if (shipped.foreign.count(section)) continue;
      const config::SectionBase* decl = nullptr;
      for (const auto* s : shipped.sections)
        if (config::sameName(s->name(), section)) decl = s;
      ASSERT_NE(decl, nullptr) << name << ": [" << section << "] is not a section of this file";
      const auto& documented = doc.keys.count(section)
                                   ? doc.keys.at(section)
                                   : std::map<std::string, std::pair<std::string, bool>>{};
      std::set<std::string> declared;
      for (const config::KeyInfo& k : decl->keys()) {
        declared.insert(k.name);
        const auto found = documented.find(k.name);
        ASSERT_NE(found, documented.end())
            << name << ": [" << section << "] " << k.name << " is not documented";
        const auto& [value, commented] = found->second;
        std::string error;
        const std::string canonical = decl->canonical(k.name, value, error);
        EXPECT_EQ(error, "") << name << ": [" << section << "] " << k.name;
        if (commented || shipped.all_defaults) {
          EXPECT_EQ(canonical, k.default_value)
              << name << ": [" << section << "] " << k.name << " shows " << value
              << " as its default; the code's default is " << k.default_value;
        }
      }
      for (const auto& [key, value] : documented) {
        const auto& foreign = decl->foreignKeys();
        EXPECT_TRUE(declared.count(key) ||
                    std::find(foreign.begin(), foreign.end(), key) != foreign.end())
            << name << ": [" << section << "] " << key << " is not a key of the section";
      }
    }
    EXPECT_NO_THROW(shipped.load(entry.path().string())) << name;
    ++files;
  }
  EXPECT_GE(files, 3u);
}
