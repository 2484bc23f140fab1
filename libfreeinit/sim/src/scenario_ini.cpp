#include <freeinit/io/atomic_file.h>
#include <freeinit/sim/presets.h>
#include <freeinit/sim/random_scenario.h>
#include <freeinit/sim/scenario_ini.h>

#include <cmath>
#include <limits>
#include <ostream>
#include <sstream>
#include <stdexcept>

namespace freeinit::sim {
namespace {

using config::formatNumber;
using config::quote;
using C = ScenarioConfig;
using Text = std::string;

constexpr const char* kSection = "scenario";
/// At most this many explicitly placed objects: a written file stays far below the size an INI
/// file may have (config::IniFile::kMaxBytes).
constexpr std::size_t kMaxObjects = 1000;

// ---- text <-> values of the keys that are not plain numbers ----------------------------------

std::vector<std::string_view> words(std::string_view s) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
    std::size_t j = i;
    while (j < s.size() && s[j] != ' ' && s[j] != '\t') ++j;
    if (j > i) out.push_back(s.substr(i, j - i));
    i = j;
  }
  return out;
}

/// Numbers separated by blanks (at least one).
Text toReals(std::string_view s, std::vector<double>& out) {
  out.clear();
  for (std::string_view w : words(s)) {
    double x = 0;
    if (Text err = config::parseNumber(w, x); !err.empty()) return err;
    out.push_back(x);
  }
  return out.empty() ? "expected numbers or none" : "";
}

Text vecText(const Vec3& v) {
  return formatNumber(v.x()) + " " + formatNumber(v.y()) + " " + formatNumber(v.z());
}

Text polyText(const std::vector<double>& p) {
  if (p.empty()) return "none";
  Text out;
  for (double c : p) out += (out.empty() ? "" : " ") + formatNumber(c);
  return out;
}

Text toPoly(std::string_view s, std::vector<double>& p) {
  if (s == "none") {
    p.clear();
    return "";
  }
  return toReals(s, p);
}

Text wavesText(const std::vector<Sinusoid>& waves) {
  if (waves.empty()) return "none";
  Text out;
  for (const Sinusoid& w : waves)
    out += (out.empty() ? "" : ", ") + formatNumber(w.amplitude) + " " + formatNumber(w.freq_hz) +
           " " + formatNumber(w.phase);
  return out;
}

Text toWaves(std::string_view s, std::vector<Sinusoid>& waves) {
  waves.clear();
  if (s == "none") return "";
  std::size_t b = 0;
  while (true) {
    const auto e = s.find(',', b);
    std::vector<double> x;
    const std::string_view part = s.substr(b, e == std::string_view::npos ? e : e - b);
    if (Text err = toReals(part, x); !err.empty() || x.size() != 3)
      return err.empty() ? "expected 'amplitude freq_hz phase', got " + quote(part) : err;
    if (!(x[1] >= 0)) return "frequencies must be >= 0";
    waves.push_back(Sinusoid{x[0], x[1], x[2]});
    if (e == std::string_view::npos) return "";
    b = e + 1;
  }
}

Text objectText(const SceneObject& o) {
  return Text(o.shape == ObjectShape::Cylinder ? "cylinder" : "box") + " " + o.label + " " +
         vecText(o.center) + " " + vecText(o.half_size) + " " + formatNumber(o.yaw) + " " +
         vecText(o.velocity) + " " + formatNumber(o.reflectivity);
}

Text checkObject(const SceneObject& o) {
  if (!(o.half_size.minCoeff() > 0)) return "half sizes must be > 0";
  if (!(o.reflectivity >= 0 && o.reflectivity <= 1)) return "reflectivity must be in [0, 1]";
  if (o.label.empty() || o.label.find_first_not_of("abcdefghijklmnopqrstuvwxyz_") != Text::npos)
    return "label must be a word of a-z and _";
  if (!o.center.allFinite() || !o.velocity.allFinite() || !std::isfinite(o.yaw))
    return "numbers must be finite";
  return "";
}

Text toObject(std::string_view s, SceneObject& o) {
  const auto w = words(s);
  if (w.size() != 13)
    return "expected 'box|cylinder label cx cy cz hx hy hz yaw vx vy vz reflectivity', got " +
           quote(s);
  if (w[0] == "box") {
    o.shape = ObjectShape::Box;
  } else if (w[0] == "cylinder") {
    o.shape = ObjectShape::Cylinder;
  } else {
    return "shape must be box or cylinder, got " + quote(w[0]);
  }
  o.label = Text(w[1]);
  std::vector<double> x(11);
  for (std::size_t i = 2; i < w.size(); ++i)
    if (Text err = config::parseNumber(w[i], x[i - 2]); !err.empty()) return err;
  o.center = Vec3(x[0], x[1], x[2]);
  o.half_size = Vec3(x[3], x[4], x[5]);
  o.yaw = x[6];
  o.velocity = Vec3(x[7], x[8], x[9]);
  o.reflectivity = x[10];
  return "";
}

bool allFinite(const ScalarSignal& s) {
  for (double p : s.poly)
    if (!std::isfinite(p)) return false;
  for (const Sinusoid& w : s.waves)
    if (!std::isfinite(w.amplitude) || !std::isfinite(w.phase) || !std::isfinite(w.freq_hz))
      return false;
  return true;
}

/// The two keys of one motion channel (0..2 position x y z, 3..5 roll pitch yaw).
void addChannel(config::Section<C>& s, int channel) {
  static const char* const kNames[] = {"x", "y", "z", "roll", "pitch", "yaw"};
  const Text name = kNames[channel];
  const bool angle = channel >= 3;
  auto signal = [channel](auto& c) -> auto& {
    return channel < 3 ? c.motion.pos[static_cast<std::size_t>(channel)]
                       : c.motion.rpy[static_cast<std::size_t>(channel - 3)];
  };
  s.custom(
       name + "_poly", [signal](auto& c) -> auto& { return signal(c).poly; },
       angle ? "rad/s^k" : "m/s^k", "numbers c0 c1 ... or none",
       std::function<Text(std::string_view, std::vector<double>&)>(toPoly),
       std::function<Text(const std::vector<double>&)>(polyText),
       "polynomial part of the " + name + " signal: sum c_k tau^k")
      .custom(
          name + "_waves", [signal](auto& c) -> auto& { return signal(c).waves; },
          angle ? "rad, Hz, rad" : "m, Hz, rad", "amplitude freq_hz phase, ... (freq >= 0) or none",
          std::function<Text(std::string_view, std::vector<Sinusoid>&)>(toWaves),
          std::function<Text(const std::vector<Sinusoid>&)>(wavesText),
          "sinusoids of the " + name + " signal: A sin(2 pi f tau + phase)");
}

config::Section<C> buildSection() {
  using config::above;
  using config::any;
  using config::atLeast;
  using config::between;
  const config::Range open0to180{0, 180, true, true};
  config::Section<C> s(kSection);
  // Origin, seed, timing.
  std::vector<std::pair<Text, Text>> bases;
  for (const Text& n : presetNames()) bases.emplace_back(n, n);
  bases.emplace_back("random", "random");
  s.choice("preset", &C::name, bases,
           "the base scenario the other keys override (random: randomScenario(seed))")
      .custom("seed", &C::seed, "-", "[0, 2^64), whole",
              std::function<Text(std::string_view, std::uint64_t&)>(
                  [](std::string_view text, std::uint64_t& seed) {
                    long double x = 0;
                    Text err = config::parseInteger(
                        text, 0,
                        static_cast<long double>(std::numeric_limits<std::uint64_t>::max()), x);
                    if (err.empty()) seed = static_cast<std::uint64_t>(x);
                    return err;
                  }),
              std::function<Text(const std::uint64_t&)>(
                  [](const std::uint64_t& seed) { return std::to_string(seed); }),
              "seeds the base, the scene layout, the noise and the seeded draws")
      .number("t0", &C::t0, "s", above(0), "UNIX time of the first sample")
      .number("duration", &C::duration, "s", above(0), "recording length");
  // Motion.
  s.vector3(
       "start_position", [](auto& c) -> auto& { return c.motion.start_position; }, "m", any(),
       "rig (IMU origin) in the path frame when motion starts")
      .vector3(
          "start_rpy_deg", [](auto& c) -> auto& { return c.motion.start_rpy_deg; }, "deg", any(),
          "rig roll pitch yaw then (R = Rz Ry Rx)")
      .number(
          "still_until", [](auto& c) -> auto& { return c.motion.still_until; }, "s", atLeast(0),
          "motion starts this long after t0")
      .number(
          "blend_duration", [](auto& c) -> auto& { return c.motion.blend_duration; }, "s", any(),
          "smoothstep from rest into motion; <= 0: moving from the first instant")
      .flag(
          "ramp_poly", [](auto& c) -> auto& { return c.motion.ramp_poly; },
          "the polynomial parts enter through their rates: the speed ramps up, no overshoot");
  for (int ch = 0; ch < 6; ++ch) addChannel(s, ch);
  s.vector3(
       "imu_mount_rpy_deg", [](auto& c) -> auto& { return c.motion.imu_mount_rpy_deg; }, "deg",
       any(), "IMU (body) on the rig: R_rb")
      .number(
          "heading_deg", [](auto& c) -> auto& { return c.motion.heading_deg; }, "deg", any(),
          "yaw of the path frame (scene and motion) in the world");
  // Scene.
  std::vector<std::pair<Text, Text>> kinds;
  for (const char* k : {"street", "corridor", "tunnel", "open", "parking"})
    kinds.emplace_back(k, k);
  auto kind = [](const char* k) { return [k](const C& c) { return c.scene.kind == k; }; };
  auto fixed_extent = [](const C& c) { return !c.scene.auto_extent; };
  s.choice(
       "scene", [](auto& c) -> auto& { return c.scene.kind; }, kinds,
       "scene kind, laid out by its builder with the seed")
      .flag(
          "scene_auto_extent", [](auto& c) -> auto& { return c.scene.auto_extent; },
          "lay the scene out along the stretch covered within the duration")
      .number(
          "scene_x_min", [](auto& c) -> auto& { return c.scene.x_min; }, "m", any(),
          "start of the stretch laid out (no auto extent)")
      .when(fixed_extent)
      .number(
          "scene_x_max", [](auto& c) -> auto& { return c.scene.x_max; }, "m", any(),
          "end of the stretch laid out, > scene_x_min")
      .when(fixed_extent)
      .number(
          "scene_horizon", [](auto& c) -> auto& { return c.scene.horizon; }, "s", above(0),
          "time moving objects are placed for")
      .when(fixed_extent)
      .number(
          "street_half_width", [](auto& c) -> auto& { return c.scene.street.half_width; }, "m",
          between(6.5, 100), "facade-to-centre distance")
      .when(kind("street"))
      .number(
          "street_cars_per_100m", [](auto& c) -> auto& { return c.scene.street.cars_per_100m; },
          "-", between(0, 50), "moving cars per 100 m and lane")
      .when(kind("street"))
      .number(
          "street_pedestrians_per_100m",
          [](auto& c) -> auto& { return c.scene.street.pedestrians_per_100m; }, "-",
          between(0, 100), "pedestrians per 100 m and sidewalk")
      .when(kind("street"))
      .number(
          "street_ego_lane_speed", [](auto& c) -> auto& { return c.scene.street.ego_lane_speed; },
          "m/s", atLeast(0),
          "> 0: the platform drives in lane y = -2.5, its lane's cars ahead and faster")
      .when(kind("street"))
      .flag(
          "street_near_traffic", [](auto& c) -> auto& { return c.scene.street.near_traffic; },
          "the presets' traffic placed near the start")
      .when(kind("street"))
      .number(
          "corridor_half_width", [](auto& c) -> auto& { return c.scene.corridor.half_width; }, "m",
          between(0.5, 20), "wall-to-centre distance")
      .when(kind("corridor"))
      .number(
          "corridor_height", [](auto& c) -> auto& { return c.scene.corridor.height; }, "m",
          between(1.5, 20), "floor to ceiling")
      .when(kind("corridor"))
      .number(
          "corridor_pedestrians", [](auto& c) -> auto& { return c.scene.corridor.pedestrians; },
          "-", between(0, 100), "people walking along the corridor")
      .when(kind("corridor"))
      .number(
          "corridor_pedestrian_offset",
          [](auto& c) -> auto& { return c.scene.corridor.pedestrian_offset; }, "m", atLeast(0),
          "|y| of the people's paths")
      .when(kind("corridor"))
      .number(
          "tunnel_half_width", [](auto& c) -> auto& { return c.scene.tunnel.half_width; }, "m",
          between(0.5, 50), "wall-to-centre distance")
      .when(kind("tunnel"))
      .number(
          "tunnel_height", [](auto& c) -> auto& { return c.scene.tunnel.height; }, "m",
          between(1.5, 50), "floor to ceiling")
      .when(kind("tunnel"))
      .number(
          "tunnel_features_per_100m",
          [](auto& c) -> auto& { return c.scene.tunnel.features_per_100m; }, "-", between(0, 200),
          "lights, niches and signs per 100 m (0: featureless)")
      .when(kind("tunnel"))
      .number(
          "open_pedestrians", [](auto& c) -> auto& { return c.scene.open.pedestrians; }, "-",
          between(0, 100), "people walking at |y| 8-14 m")
      .when(kind("open"))
      .number(
          "parking_aisle_half_width",
          [](auto& c) -> auto& { return c.scene.parking.aisle_half_width; }, "m", between(1.5, 20),
          "free half width of the aisle")
      .when(kind("parking"))
      .number(
          "parking_occupancy", [](auto& c) -> auto& { return c.scene.parking.occupancy; }, "-",
          between(0, 1), "share of occupied bays")
      .when(kind("parking"))
      .number(
          "parking_pedestrians", [](auto& c) -> auto& { return c.scene.parking.pedestrians; }, "-",
          between(0, 100), "people walking along the aisle")
      .when(kind("parking"))
      .number(
          "parking_moving_cars", [](auto& c) -> auto& { return c.scene.parking.moving_cars; }, "-",
          between(0, 100), "cars driving in the parallel aisles")
      .when(kind("parking"));
  using Objects = std::vector<SceneObject>;
  s.custom(
       "objects", [](auto& c) -> auto& { return c.scene.objects; }, "-",
       "[0, " + std::to_string(kMaxObjects) + "], whole",
       std::function<Text(std::string_view, Objects&)>([](std::string_view text, Objects& o) {
         long double n = 0;
         Text err = config::parseInteger(text, 0, kMaxObjects, n);
         if (err.empty()) o.resize(static_cast<std::size_t>(n));
         return err;
       }),
       std::function<Text(const Objects&)>(
           [](const Objects& o) { return std::to_string(o.size()); }),
       "number of explicitly placed objects (object_1 ...); new ones must be given")
      .items(
          "object_", [](auto& c) -> auto& { return c.scene.objects; }, "objects", "m, rad, m/s",
          "box|cylinder label cx cy cz hx hy hz yaw vx vy vz reflectivity",
          std::function<Text(std::string_view, SceneObject&)>(toObject),
          std::function<Text(const SceneObject&)>(objectText),
          std::function<Text(const SceneObject&)>(checkObject),
          "k-th object at t0 in the path frame (cylinder: hx = radius, hz = half height)");
  // LiDAR.
  s.number("points_per_frame", &C::points_per_frame, "-", between(0, 1e7),
           "rays per frame (misses are dropped)")
      .number("lines", &C::lines, "-", between(1, 65535), "scan lines per frame")
      .number("frame_rate", &C::frame_rate, "Hz", above(0), "frames per second")
      .number("hfov_deg", &C::hfov_deg, "deg", open0to180, "horizontal field of view")
      .number("vfov_deg", &C::vfov_deg, "deg", open0to180, "vertical field of view")
      .choice("line_order", &C::line_order,
              {{"top_down", LineOrder::TopDown},
               {"bottom_up", LineOrder::BottomUp},
               {"interleaved", LineOrder::Interleaved}},
              "order in which the lines of a frame are measured")
      .choice("line_direction", &C::line_direction,
              {{"alternating", LineDirection::Alternating}, {"forward", LineDirection::Forward}},
              "azimuth sweep: back and forth, or every line the same way")
      .number("min_range", &C::min_range, "m", atLeast(0), "closer returns are dropped")
      .number("max_range", &C::max_range, "m", above(0), "farther returns are dropped; > min_range")
      .number("range_sigma", &C::range_sigma, "m", atLeast(0), "range noise std")
      .number("doppler_sigma", &C::doppler_sigma, "m/s", atLeast(0), "Doppler noise std")
      .number("outlier_ratio", &C::outlier_ratio, "-", between(0, 1),
              "share of points with a gross Doppler error");
  // IMU.
  s.number("imu_rate", &C::imu_rate, "Hz", above(0), "IMU samples per second")
      .number("gyro_sigma", &C::gyro_sigma, "rad/s", atLeast(0),
              "gyro white noise per sample (datasheet)")
      .number("accel_sigma", &C::accel_sigma, "m/s^2", atLeast(0),
              "accelerometer white noise per sample (datasheet)")
      .vector3("gyro_sigma_scale", &C::gyro_sigma_scale, "-", atLeast(0),
               "this unit's per-axis sigma / gyro_sigma")
      .vector3("accel_sigma_scale", &C::accel_sigma_scale, "-", atLeast(0),
               "this unit's per-axis sigma / accel_sigma")
      .flag("random_biases", &C::random_biases,
            "draw the biases with the seed (the presets' ranges)")
      .vector3("b_g", &C::b_g, "rad/s", any(), "constant gyro bias (random_biases false)")
      .when([](const C& c) { return !c.random_biases; })
      .vector3("b_a", &C::b_a, "m/s^2", any(), "constant accelerometer bias (random_biases false)")
      .when([](const C& c) { return !c.random_biases; });
  // Calibration: the truth, and what is declared.
  s.vector3("lidar_rpy_deg", &C::lidar_rpy_deg, "deg", any(),
            "true R_bl = Rz(yaw) Ry(pitch) Rx(roll)")
      .vector3("lidar_position", &C::lidar_position, "m", any(), "true p_bl")
      .number("lidar_rpy_jitter_deg", &C::lidar_rpy_jitter_deg, "deg", atLeast(0),
              "seeded uniform perturbation of each angle, +-")
      .number("lidar_position_jitter", &C::lidar_position_jitter, "m", atLeast(0),
              "seeded uniform perturbation of each p_bl axis, +-")
      .vector3("declared_rotation_error_deg", &C::declared_rotation_error_deg, "deg", any(),
               "declared R_bl = true R_bl Exp(this rotation vector)")
      .vector3("declared_position_error", &C::declared_position_error, "m", any(),
               "declared p_bl = true p_bl + this")
      .number("lidar_time_offset", &C::lidar_time_offset, "s", between(-1, 1),
              "LiDAR clock minus IMU clock: LiDAR stamps = true time + this");
  // Across keys.
  s.check([](const C& c, const config::Checker& k) {
    if (!(c.max_range > c.min_range)) k.fail("max_range", "must be > min_range");
    if (!c.scene.auto_extent && !(c.scene.x_max > c.scene.x_min))
      k.fail("scene_x_max", "must be > scene_x_min");
    if (c.scene.objects.size() > kMaxObjects)
      k.fail("objects", "at most " + std::to_string(kMaxObjects));
    static const char* const kNames[] = {"x", "y", "z", "roll", "pitch", "yaw"};
    for (std::size_t ch = 0; ch < 6; ++ch) {
      const ScalarSignal& sig = ch < 3 ? c.motion.pos[ch] : c.motion.rpy[ch - 3];
      if (!allFinite(sig))
        k.fail(Text(kNames[ch]) + "_waves", "coefficients, amplitudes and phases must be finite");
      for (const Sinusoid& w : sig.waves)
        if (!(w.freq_hz >= 0)) k.fail(Text(kNames[ch]) + "_waves", "frequencies must be >= 0");
    }
  });
  return s;
}

}  // namespace

const config::Section<ScenarioConfig>& scenarioSection() {
  static const config::Section<ScenarioConfig> kSectionDecl = buildSection();
  return kSectionDecl;
}

void validateScenario(const ScenarioConfig& c) { scenarioSection().validate(c); }

std::string scenarioKeysHelp() {
  std::ostringstream o;
  o << "[scenario] keys (default: preset dyna_01, seed 1)\n";
  for (const config::KeyInfo& k : scenarioSection().keys()) {
    o << k.name << " [" << k.unit << "]";
    if (!k.default_value.empty()) o << " = " << k.default_value;
    if (!k.accepted.empty()) o << "  (" << k.accepted << ")";
    o << "  " << k.doc << "\n";
  }
  return o.str();
}

ScenarioConfig scenarioFromIni(const config::IniFile& ini, const ScenarioBase& base) {
  ini.requireKnownSections({kSection});
  const config::IniSection* sec = ini.section(kSection);
  if (!sec) throw config::ConfigError(ini.where(0) + ": no [scenario] section");
  const auto& decl = scenarioSection();
  // The base: `preset` and `seed`, read by their declarations.
  auto baseKey = [&](const char* key, const Text& fallback) {
    const config::IniEntry* e = sec->find(key);
    if (!e) return fallback;
    Text error;
    Text value = decl.canonical(key, e->value, error);
    if (!error.empty()) ini.fail(kSection, key, error);
    return value;
  };
  const Text name = baseKey("preset", base.preset);
  const std::uint64_t seed = std::stoull(baseKey("seed", std::to_string(base.seed)));
  ScenarioConfig c;
  try {
    c = name == "random" ? randomScenario(seed) : preset(name, seed);
  } catch (const std::invalid_argument& e) {
    ini.fail(kSection, "preset", e.what());
  }
  decl.load(ini, c);
  const config::Checker given(&ini, kSection);
  if ((given.has("b_g") || given.has("b_a")) && !given.has("random_biases"))
    c.random_biases = false;
  return c;
}

ScenarioConfig loadScenarioIni(const std::string& path, const ScenarioBase& base) {
  return scenarioFromIni(config::IniFile::load(path), base);
}

ScenarioConfig scenarioFromKeys(const ScenarioKeyValues& section, const ScenarioBase& base) {
  config::IniFile ini("scenario keys");
  config::IniSection sec;
  sec.name = kSection;
  for (const auto& [key, value] : section) sec.entries.push_back({key, value, 0, ""});
  ini.add(std::move(sec));
  return scenarioFromIni(ini, base);
}

std::string scenarioIni(const ScenarioConfig& c, const std::vector<std::string>& comments) {
  std::ostringstream o;
  for (const std::string& line : comments) o << "; " << line << "\n";
  scenarioSection().dump(c, o);
  return o.str();
}

void writeScenarioIni(const std::string& path, const ScenarioConfig& config,
                      const std::vector<std::string>& comments) {
  const std::string text = scenarioIni(config, comments);
  writeFileAtomically(path, [&](std::ostream& out) { out << text; });
}

}  // namespace freeinit::sim
