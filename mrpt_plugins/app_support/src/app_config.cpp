// INI declarations, loading and echo of AppConfig. Each section is declared once (keys, units,
// accepted values, docs); that declaration drives loading, validation and the dump, so that the
// documented INI and the loader cannot drift apart.
#include <freeinit/app_support/app_config.h>
#include <freeinit/io/config_section.h>

#include <Eigen/Geometry>
#include <cmath>
#include <ostream>
#include <sstream>

namespace freeinit::app_support {
namespace {

using config::between;
using config::Checker;

std::string parseRotation(std::string_view text, Mat3& R) {
  std::vector<double> v;
  if (std::string err = config::parseNumbers(text, 9, v); !err.empty()) return err;
  Mat3 M;
  M << v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8];
  const double orth = (M.transpose() * M - Mat3::Identity()).norm();
  const double det = M.determinant();
  if (orth > 1e-4 || std::abs(det - 1.0) > 1e-4) {
    std::ostringstream os;
    os << "not a rotation matrix (|R^T R - I| = " << orth << ", det = " << det << ")";
    return os.str();
  }
  R = M;
  return "";
}

std::string formatRotation(const Mat3& R) {
  std::string s;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) s += (s.empty() ? "" : " ") + config::formatNumber(R(i, j));
  return s;
}

// The pose keys, added to the section of any struct that holds a LidarPoseParams.
template <class S, class Pose>
config::Section<S>& addPoseKeys(config::Section<S>& s, Pose pose) {
  return s
      .custom(
          "R_bl", [pose](auto& x) -> auto& { return pose(x).R_bl; }, "-",
          "9 numbers, row-major, a rotation",
          std::function<std::string(std::string_view, Mat3&)>(parseRotation),
          std::function<std::string(const Mat3&)>(formatRotation),
          "LiDAR-to-IMU rotation, row-major")
      .number(
          "roll_deg", [pose](auto& x) -> auto& { return pose(x).roll_deg; }, "deg",
          between(-360, 360), "instead of R_bl: R_bl = Rz(yaw) Ry(pitch) Rx(roll)")
      .number(
          "pitch_deg", [pose](auto& x) -> auto& { return pose(x).pitch_deg; }, "deg",
          between(-360, 360), "instead of R_bl (see roll_deg)")
      .number(
          "yaw_deg", [pose](auto& x) -> auto& { return pose(x).yaw_deg; }, "deg",
          between(-360, 360), "instead of R_bl (see roll_deg)")
      .vector3(
          "p_bl", [pose](auto& x) -> auto& { return pose(x).p_bl; }, "m", between(-100, 100),
          "LiDAR origin in the IMU frame");
}

constexpr const char* kPoseKeys[] = {"R_bl", "roll_deg", "pitch_deg", "yaw_deg", "p_bl"};

void loadExtrinsics(const config::IniFile& ini, AppConfig& c) {
  ExtrinsicsIniParams x;
  extrinsicsSection().load(ini, x);
  const Checker keys(&ini, "extrinsics");
  c.core.extrinsics = extrinsicsOf(x.pose, keys);
  const std::string given = firstPoseKey(keys);
  c.extrinsics.from_sensor_pose = x.from_sensor_pose;
  c.extrinsics.given_in_ini = !given.empty();
  if (!given.empty() && x.from_sensor_pose)
    keys.fail(given, keys.has("from_sensor_pose")
                         ? "given, but from_sensor_pose = true: choose one"
                         : "given, but from_sensor_pose is true (the default: the extrinsics of "
                           "the observations' sensorPose): set from_sensor_pose = false to use "
                           "the INI's extrinsics");
  if (given.empty() && !x.from_sensor_pose)
    keys.fail("from_sensor_pose",
              "false, but no extrinsics are given: give R_bl (or roll_deg, pitch_deg, yaw_deg) "
              "and p_bl");
}

}  // namespace

const config::Section<InputParams>& inputSection() {
  using P = InputParams;
  static const auto s =
      config::Section<P>("input", "how observations are picked from the rawlog")
          .text("imu_label", &P::imu_label, "sensorLabel of the IMU observations (empty: any)")
          .text("lidar_label", &P::lidar_label,
                "sensorLabel of the point-cloud observations (empty: any)")
          .flag("imu_accel_in_g", &P::imu_accel_in_g,
                "accelerometer given in g (converted with 9.81); otherwise m/s^2")
          .number("min_imu_rate", &P::min_imu_rate, "Hz", between(1, 1e5),
                  "slower IMU streams are rejected")
          .flag("drop_invalid_points", &P::drop_invalid_points,
                "drop NaN/inf points (reported) instead of failing")
          .number("doppler_resolution", &P::doppler_resolution, "m/s", between(0, 10),
                  "the sensor's Doppler bin (0: continuous); with bins, a cloud with zero "
                  "Doppler everywhere is accepted moving too, otherwise only while the IMU "
                  "shows rest")
          .number("max_record_mb", &P::max_record_mb, "MB", between(1, 65536),
                  "most one rawlog record may allocate while it is read (a 60,000-point cloud "
                  "takes 1.6 MB); a record claiming more is corrupt and refused");
  return s;
}

const config::Section<ExtrinsicsIniParams>& extrinsicsSection() {
  static const auto s = [] {
    config::Section<ExtrinsicsIniParams> sec(
        "extrinsics",
        "the LiDAR pose in the IMU (body) frame: from the observations' sensorPose, or R_bl (or "
        "roll_deg, pitch_deg, yaw_deg) and p_bl with from_sensor_pose = false");
    sec.flag("from_sensor_pose", &ExtrinsicsIniParams::from_sensor_pose,
             "take the extrinsics from the observations' sensorPose (LiDAR pose w.r.t. the IMU "
             "pose), as freeinit-sim and freeinit-import-bag write them");
    addPoseKeys(
        sec, [](auto& x) -> auto& { return x.pose; });
    return sec;
  }();
  return s;
}

const config::Section<LidarPoseParams>& extrinsicsPoseSection() {
  static const auto s = [] {
    config::Section<LidarPoseParams> sec(
        "extrinsics",
        "the LiDAR pose in the IMU (body) frame: R_bl (or roll_deg, pitch_deg, "
        "yaw_deg) and p_bl");
    addPoseKeys(
        sec, [](auto& x) -> auto& { return x; });
    sec.refused("from_sensor_pose",
                "a bag has no sensor poses: give R_bl (or roll_deg, pitch_deg, yaw_deg) and p_bl");
    return sec;
  }();
  return s;
}

std::vector<const config::SectionBase*> appSections() {
  std::vector<const config::SectionBase*> sections = FreeInitConfig::sections();
  sections.insert(sections.end(), {&inputSection(), &outputSection(), &extrinsicsSection()});
  return sections;
}

Extrinsics extrinsicsOf(const LidarPoseParams& pose, const Checker& keys) {
  const bool has_angles = keys.has("roll_deg") || keys.has("pitch_deg") || keys.has("yaw_deg");
  if (keys.has("R_bl") && has_angles)
    keys.fail("R_bl", "give either R_bl or roll_deg/pitch_deg/yaw_deg, not both");
  Extrinsics e;
  e.R_bl = pose.R_bl;
  if (has_angles) {
    constexpr double kDeg = M_PI / 180.0;
    e.R_bl = (Eigen::AngleAxisd(pose.yaw_deg * kDeg, Vec3::UnitZ()) *
              Eigen::AngleAxisd(pose.pitch_deg * kDeg, Vec3::UnitY()) *
              Eigen::AngleAxisd(pose.roll_deg * kDeg, Vec3::UnitX()))
                 .toRotationMatrix();
  }
  e.p_bl = pose.p_bl;
  return e;
}

std::string firstPoseKey(const Checker& keys) {
  for (const char* k : kPoseKeys)
    if (keys.has(k)) return k;
  return "";
}

AppConfig loadAppConfig(const config::IniFile& ini, std::vector<std::string>* notices) {
  std::vector<std::string> names;
  for (const auto* s : appSections()) names.push_back(s->name());
  ini.requireKnownSections(names, FreeInitConfig::formerSectionNames());
  AppConfig c;
  c.core.load(ini, notices);
  inputSection().load(ini, c.input);
  outputSection().load(ini, c.output);
  loadExtrinsics(ini, c);
  return c;
}

AppConfig loadAppConfig(const std::string& ini_file, std::vector<std::string>* notices) {
  return loadAppConfig(config::IniFile::load(ini_file), notices);
}

AppConfig loadAppConfigFromText(const std::string& ini_text, const std::string& source,
                                std::vector<std::string>* notices) {
  return loadAppConfig(config::IniFile::parse(ini_text, source), notices);
}

void dumpAppConfig(const AppConfig& c, std::ostream& out) {
  c.core.dump(out);
  out << "\n";
  inputSection().dump(c.input, out);
  out << "\n";
  outputSection().dump(c.output, out);
  out << "\n";
  // [extrinsics] in its canonical form: from_sensor_pose, and R_bl and p_bl when they are used
  // (shown commented out otherwise, so that the echo loads back).
  ExtrinsicsIniParams x;
  x.from_sensor_pose = c.extrinsics.from_sensor_pose;
  x.pose.R_bl = c.core.extrinsics.R_bl;
  x.pose.p_bl = c.core.extrinsics.p_bl;
  const auto& sec = extrinsicsSection();
  sec.dumpHeader(out);
  sec.dumpKey(x, "from_sensor_pose", out);
  sec.dumpKey(x, "R_bl", out, x.from_sensor_pose);
  sec.dumpKey(x, "p_bl", out, x.from_sensor_pose);
}

}  // namespace freeinit::app_support
