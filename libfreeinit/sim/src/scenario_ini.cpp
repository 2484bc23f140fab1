#include <freeinit/atomic_file.h>
#include <freeinit/sim/presets.h>
#include <freeinit/sim/random_scenario.h>
#include <freeinit/sim/scenario_ini.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <map>
#include <ostream>
#include <set>
#include <sstream>
#include <stdexcept>

namespace freeinit::sim {
namespace {

using Text = std::string;

// ---- text <-> values -------------------------------------------------------------------------

Text trim(const Text& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == Text::npos) return "";
  const auto e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

std::vector<Text> split(const Text& s, char sep) {
  std::vector<Text> out;
  std::size_t b = 0;
  while (true) {
    const auto e = s.find(sep, b);
    out.push_back(trim(s.substr(b, e == Text::npos ? Text::npos : e - b)));
    if (e == Text::npos) return out;
    b = e + 1;
  }
}

std::vector<Text> words(const Text& s) {
  std::vector<Text> out;
  std::istringstream is(s);
  for (Text w; is >> w;) out.push_back(w);
  return out;
}

/// Shortest text that reads back as exactly x (fixed notation unless that is long).
Text fmt(double x) {
  char buf[400];
  const auto fixed = std::to_chars(buf, buf + sizeof buf, x, std::chars_format::fixed);
  if (fixed.ec == std::errc() && fixed.ptr - buf <= 24) return Text(buf, fixed.ptr);
  const auto r = std::to_chars(buf, buf + sizeof buf, x);
  return Text(buf, r.ptr);
}

double toReal(const Text& w) {
  double x = 0;
  const char* end = w.data() + w.size();
  const char* begin = w.data() + (!w.empty() && w[0] == '+' ? 1 : 0);
  const auto r = std::from_chars(begin, end, x);
  if (w.empty() || r.ec != std::errc() || r.ptr != end || !std::isfinite(x))
    throw std::invalid_argument("expected a number, got '" + w + "'");
  return x;
}

std::vector<double> toReals(const Text& s, std::size_t n_exact = 0) {
  std::vector<double> out;
  for (const Text& w : words(s)) out.push_back(toReal(w));
  if (n_exact > 0 && out.size() != n_exact)
    throw std::invalid_argument("expected " + std::to_string(n_exact) + " numbers, got '" + s +
                                "'");
  return out;
}

template <typename Int>
Int toInteger(const Text& s) {
  const Text w = trim(s);
  Int x = 0;
  const auto r = std::from_chars(w.data(), w.data() + w.size(), x);
  if (w.empty() || r.ec != std::errc() || r.ptr != w.data() + w.size())
    throw std::invalid_argument("expected a whole number, got '" + w + "'");
  return x;
}

bool toBool(const Text& s) {
  Text w = trim(s);
  std::transform(w.begin(), w.end(), w.begin(), [](unsigned char ch) { return std::tolower(ch); });
  if (w == "true" || w == "1" || w == "yes") return true;
  if (w == "false" || w == "0" || w == "no") return false;
  throw std::invalid_argument("expected true or false, got '" + w + "'");
}

Text vecText(const Vec3& v) { return fmt(v.x()) + " " + fmt(v.y()) + " " + fmt(v.z()); }

Vec3 toVec3(const Text& s) {
  const auto x = toReals(s, 3);
  return Vec3(x[0], x[1], x[2]);
}

Text polyText(const std::vector<double>& p) {
  if (p.empty()) return "none";
  Text out;
  for (double c : p) out += (out.empty() ? "" : " ") + fmt(c);
  return out;
}

std::vector<double> toPoly(const Text& s) {
  if (trim(s) == "none") return {};
  auto p = toReals(s);
  if (p.empty()) throw std::invalid_argument("expected coefficients or none");
  return p;
}

Text wavesText(const std::vector<Sinusoid>& waves) {
  if (waves.empty()) return "none";
  Text out;
  for (const Sinusoid& w : waves) {
    out += (out.empty() ? "" : ", ") + fmt(w.amplitude) + " " + fmt(w.freq_hz) + " " + fmt(w.phase);
  }
  return out;
}

std::vector<Sinusoid> toWaves(const Text& s) {
  if (trim(s) == "none") return {};
  std::vector<Sinusoid> out;
  for (const Text& part : split(s, ',')) {
    const auto x = toReals(part, 3);
    out.push_back(Sinusoid{x[0], x[1], x[2]});
  }
  return out;
}

// ---- ranges ----------------------------------------------------------------------------------

struct Range {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool lo_open = false, hi_open = false;
  bool contains(double x) const {
    return std::isfinite(x) && (lo_open ? x > lo : x >= lo) && (hi_open ? x < hi : x <= hi);
  }
  Text text() const {
    const bool has_lo = std::isfinite(lo), has_hi = std::isfinite(hi);
    if (!has_lo && !has_hi) return "any";
    if (!has_hi) return (lo_open ? "> " : ">= ") + fmt(lo);
    if (!has_lo) return (hi_open ? "< " : "<= ") + fmt(hi);
    return Text(lo_open ? "(" : "[") + fmt(lo) + ", " + fmt(hi) + (hi_open ? ")" : "]");
  }
};

Range any() { return {}; }
Range positive() { return {0, std::numeric_limits<double>::infinity(), true, false}; }
Range nonNegative() { return {0, std::numeric_limits<double>::infinity(), false, false}; }
Range closed(double a, double b) { return {a, b, false, false}; }
Range open(double a, double b) { return {a, b, true, true}; }

Text outOf(const Range& r) {
  return (std::isfinite(r.lo) && std::isfinite(r.hi) ? "must be in " : "must be ") + r.text();
}

// ---- table builders --------------------------------------------------------------------------

template <typename T>
using Access = T& (*)(ScenarioConfig&);

bool always(const ScenarioConfig&) { return true; }

template <typename T>
T& at(const ScenarioConfig& c, Access<T> access) {
  // The accessors only select a field; reading through them does not modify the config.
  return access(const_cast<ScenarioConfig&>(c));
}

ScenarioKey real(const char* name, const char* unit, Range range, const char* doc,
                 Access<double> access, bool (*applies)(const ScenarioConfig&) = always) {
  ScenarioKey k;
  k.name = name;
  k.unit = unit;
  k.range = range.text();
  k.doc = doc;
  k.format = [access](const ScenarioConfig& c, int) { return fmt(at(c, access)); };
  k.parse = [access](const Text& s, ScenarioConfig& c, int) {
    const auto x = toReals(s, 1);
    access(c) = x[0];
  };
  k.check = [access, range](const ScenarioConfig& c, int) {
    return range.contains(at(c, access)) ? Text() : outOf(range);
  };
  k.applies = applies;
  return k;
}

ScenarioKey integer(const char* name, long lo, long hi, const char* doc, Access<int> access,
                    bool (*applies)(const ScenarioConfig&) = always) {
  ScenarioKey k;
  k.name = name;
  k.unit = "-";
  k.range = "[" + std::to_string(lo) + ", " + std::to_string(hi) + "], whole";
  k.doc = doc;
  k.format = [access](const ScenarioConfig& c, int) { return std::to_string(at(c, access)); };
  k.parse = [access](const Text& s, ScenarioConfig& c, int) { access(c) = toInteger<int>(s); };
  k.check = [access, lo, hi, range = k.range](const ScenarioConfig& c, int) {
    const long x = at(c, access);
    return x >= lo && x <= hi ? Text() : "must be in " + range;
  };
  k.applies = applies;
  return k;
}

ScenarioKey vec3(const char* name, const char* unit, Range range, const char* doc,
                 Access<Vec3> access, bool (*applies)(const ScenarioConfig&) = always) {
  ScenarioKey k;
  k.name = name;
  k.unit = unit;
  k.range = "three numbers, each " + range.text();
  k.doc = doc;
  k.format = [access](const ScenarioConfig& c, int) { return vecText(at(c, access)); };
  k.parse = [access](const Text& s, ScenarioConfig& c, int) { access(c) = toVec3(s); };
  k.check = [access, range](const ScenarioConfig& c, int) {
    const Vec3& v = at(c, access);
    for (int i = 0; i < 3; ++i)
      if (!range.contains(v[i])) return "each component " + outOf(range);
    return Text();
  };
  k.applies = applies;
  return k;
}

ScenarioKey flag(const char* name, const char* doc, Access<bool> access,
                 bool (*applies)(const ScenarioConfig&) = always) {
  ScenarioKey k;
  k.name = name;
  k.range = "true|false";
  k.doc = doc;
  k.format = [access](const ScenarioConfig& c, int) {
    return Text(at(c, access) ? "true" : "false");
  };
  k.parse = [access](const Text& s, ScenarioConfig& c, int) { access(c) = toBool(s); };
  k.check = [](const ScenarioConfig&, int) { return Text(); };
  k.applies = applies;
  return k;
}

template <typename E>
ScenarioKey choice(const char* name, const char* doc, std::vector<std::pair<Text, E>> values,
                   Access<E> access) {
  ScenarioKey k;
  k.name = name;
  for (const auto& [w, e] : values) k.range += (k.range.empty() ? "" : "|") + w;
  k.doc = doc;
  k.format = [access, values](const ScenarioConfig& c, int) {
    for (const auto& [w, e] : values)
      if (e == at(c, access)) return w;
    return Text("?");
  };
  k.parse = [access, values, range = k.range](const Text& s, ScenarioConfig& c, int) {
    for (const auto& [w, e] : values) {
      if (w == trim(s)) {
        access(c) = e;
        return;
      }
    }
    throw std::invalid_argument("expected one of " + range + ", got '" + trim(s) + "'");
  };
  k.check = [](const ScenarioConfig&, int) { return Text(); };
  k.applies = always;
  return k;
}

/// The two keys of one motion channel (0..2 position x y z, 3..5 roll pitch yaw).
void addChannel(std::vector<ScenarioKey>& keys, int channel) {
  static const char* const kNames[] = {"x", "y", "z", "roll", "pitch", "yaw"};
  const bool angle = channel >= 3;
  auto signal = [channel](ScenarioConfig& c) -> ScalarSignal& {
    return channel < 3 ? c.motion.pos[static_cast<std::size_t>(channel)]
                       : c.motion.rpy[static_cast<std::size_t>(channel - 3)];
  };
  ScenarioKey poly;
  poly.name = Text(kNames[channel]) + "_poly";
  poly.unit = angle ? "rad/s^k" : "m/s^k";
  poly.range = "numbers c0 c1 ... or none";
  poly.doc = Text("polynomial part of the ") + kNames[channel] + " signal: sum c_k tau^k";
  poly.format = [signal](const ScenarioConfig& c, int) {
    return polyText(signal(const_cast<ScenarioConfig&>(c)).poly);
  };
  poly.parse = [signal](const Text& s, ScenarioConfig& c, int) { signal(c).poly = toPoly(s); };
  poly.check = [](const ScenarioConfig&, int) { return Text(); };
  poly.applies = always;
  keys.push_back(poly);
  ScenarioKey waves;
  waves.name = Text(kNames[channel]) + "_waves";
  waves.unit = angle ? "rad, Hz, rad" : "m, Hz, rad";
  waves.range = "amplitude freq_hz phase, ... (freq >= 0) or none";
  waves.doc = Text("sinusoids of the ") + kNames[channel] + " signal: A sin(2 pi f tau + phase)";
  waves.format = [signal](const ScenarioConfig& c, int) {
    return wavesText(signal(const_cast<ScenarioConfig&>(c)).waves);
  };
  waves.parse = [signal](const Text& s, ScenarioConfig& c, int) { signal(c).waves = toWaves(s); };
  waves.check = [signal](const ScenarioConfig& c, int) {
    for (const Sinusoid& w : signal(const_cast<ScenarioConfig&>(c)).waves)
      if (!(w.freq_hz >= 0)) return Text("frequencies must be >= 0");
    return Text();
  };
  waves.applies = always;
  keys.push_back(waves);
}

Text objectText(const SceneObject& o) {
  return Text(o.shape == ObjectShape::Cylinder ? "cylinder" : "box") + " " + o.label + " " +
         vecText(o.center) + " " + vecText(o.half_size) + " " + fmt(o.yaw) + " " +
         vecText(o.velocity) + " " + fmt(o.reflectivity);
}

SceneObject toObject(const Text& s) {
  const auto w = words(s);
  if (w.size() != 13)
    throw std::invalid_argument(
        "expected 'box|cylinder label cx cy cz hx hy hz yaw vx vy vz reflectivity', got '" + s +
        "'");
  SceneObject o;
  if (w[0] == "box") {
    o.shape = ObjectShape::Box;
  } else if (w[0] == "cylinder") {
    o.shape = ObjectShape::Cylinder;
  } else {
    throw std::invalid_argument("shape must be box or cylinder, got '" + w[0] + "'");
  }
  o.label = w[1];
  std::vector<double> x;
  for (std::size_t i = 2; i < w.size(); ++i) x.push_back(toReal(w[i]));
  o.center = Vec3(x[0], x[1], x[2]);
  o.half_size = Vec3(x[3], x[4], x[5]);
  o.yaw = x[6];
  o.velocity = Vec3(x[7], x[8], x[9]);
  o.reflectivity = x[10];
  return o;
}

bool isKind(const ScenarioConfig& c, const char* kind) { return c.scene.kind == kind; }

std::vector<ScenarioKey> buildTable() {
  std::vector<ScenarioKey> t;
  // Origin, seed, timing.
  {
    ScenarioKey k;
    k.name = "preset";
    k.range = "a preset name or random";
    k.doc = "the base scenario the other keys override (random: randomScenario(seed))";
    k.format = [](const ScenarioConfig& c, int) { return c.name; };
    k.parse = [](const Text& s, ScenarioConfig& c, int) { c.name = trim(s); };
    k.check = [](const ScenarioConfig& c, int) {
      if (c.name == "random") return Text();
      for (const auto& n : presetNames())
        if (n == c.name) return Text();
      return "unknown preset '" + c.name + "'";
    };
    k.applies = always;
    t.push_back(k);
  }
  {
    ScenarioKey k;
    k.name = "seed";
    k.unit = "-";
    k.range = "[0, 2^64), whole";
    k.doc = "seeds the base, the scene layout, the noise and the seeded draws";
    k.format = [](const ScenarioConfig& c, int) { return std::to_string(c.seed); };
    k.parse = [](const Text& s, ScenarioConfig& c, int) { c.seed = toInteger<std::uint64_t>(s); };
    k.check = [](const ScenarioConfig&, int) { return Text(); };
    k.applies = always;
    t.push_back(k);
  }
  t.push_back(real("t0", "s", positive(), "UNIX time of the first sample",
                   [](ScenarioConfig& c) -> double& { return c.t0; }));
  t.push_back(real("duration", "s", positive(), "recording length",
                   [](ScenarioConfig& c) -> double& { return c.duration; }));
  // Motion.
  t.push_back(vec3("start_position", "m", any(),
                   "rig (IMU origin) in the path frame when motion starts",
                   [](ScenarioConfig& c) -> Vec3& { return c.motion.start_position; }));
  t.push_back(vec3("start_rpy_deg", "deg", any(), "rig roll pitch yaw then (R = Rz Ry Rx)",
                   [](ScenarioConfig& c) -> Vec3& { return c.motion.start_rpy_deg; }));
  t.push_back(real("still_until", "s", nonNegative(), "motion starts this long after t0",
                   [](ScenarioConfig& c) -> double& { return c.motion.still_until; }));
  t.push_back(real("blend_duration", "s", any(),
                   "smoothstep from rest into motion; <= 0: moving from the first instant",
                   [](ScenarioConfig& c) -> double& { return c.motion.blend_duration; }));
  t.push_back(
      flag("ramp_poly",
           "the polynomial parts enter through their rates: the speed ramps up, no overshoot",
           [](ScenarioConfig& c) -> bool& { return c.motion.ramp_poly; }));
  for (int ch = 0; ch < 6; ++ch) addChannel(t, ch);
  t.push_back(vec3("imu_mount_rpy_deg", "deg", any(), "IMU (body) on the rig: R_rb",
                   [](ScenarioConfig& c) -> Vec3& { return c.motion.imu_mount_rpy_deg; }));
  t.push_back(real("heading_deg", "deg", any(),
                   "yaw of the path frame (scene and motion) in the world",
                   [](ScenarioConfig& c) -> double& { return c.motion.heading_deg; }));
  // Scene.
  {
    ScenarioKey k;
    k.name = "scene";
    k.range = "street|corridor|tunnel|open|parking";
    k.doc = "scene kind, laid out by its builder with the seed";
    k.format = [](const ScenarioConfig& c, int) { return c.scene.kind; };
    k.parse = [](const Text& s, ScenarioConfig& c, int) { c.scene.kind = trim(s); };
    k.check = [range = k.range](const ScenarioConfig& c, int) {
      for (const Text& w : split(range, '|'))
        if (w == c.scene.kind) return Text();
      return "must be one of " + range;
    };
    k.applies = always;
    t.push_back(k);
  }
  t.push_back(flag("scene_auto_extent",
                   "lay the scene out along the stretch covered within the duration",
                   [](ScenarioConfig& c) -> bool& { return c.scene.auto_extent; }));
  auto fixed_extent = [](const ScenarioConfig& c) { return !c.scene.auto_extent; };
  t.push_back(real(
      "scene_x_min", "m", any(), "start of the stretch laid out (no auto extent)",
      [](ScenarioConfig& c) -> double& { return c.scene.x_min; }, fixed_extent));
  t.push_back(real(
      "scene_x_max", "m", any(), "end of the stretch laid out, > scene_x_min",
      [](ScenarioConfig& c) -> double& { return c.scene.x_max; }, fixed_extent));
  t.push_back(real(
      "scene_horizon", "s", positive(), "time moving objects are placed for",
      [](ScenarioConfig& c) -> double& { return c.scene.horizon; }, fixed_extent));
  auto street = [](const ScenarioConfig& c) { return isKind(c, "street"); };
  t.push_back(real(
      "street_half_width", "m", closed(6.5, 100), "facade-to-centre distance",
      [](ScenarioConfig& c) -> double& { return c.scene.street.half_width; }, street));
  t.push_back(real(
      "street_cars_per_100m", "-", closed(0, 50), "moving cars per 100 m and lane",
      [](ScenarioConfig& c) -> double& { return c.scene.street.cars_per_100m; }, street));
  t.push_back(real(
      "street_pedestrians_per_100m", "-", closed(0, 100), "pedestrians per 100 m and sidewalk",
      [](ScenarioConfig& c) -> double& { return c.scene.street.pedestrians_per_100m; }, street));
  t.push_back(real(
      "street_ego_lane_speed", "m/s", nonNegative(),
      "> 0: the platform drives in lane y = -2.5, its lane's cars ahead and faster",
      [](ScenarioConfig& c) -> double& { return c.scene.street.ego_lane_speed; }, street));
  t.push_back(flag(
      "street_near_traffic", "the presets' traffic placed near the start",
      [](ScenarioConfig& c) -> bool& { return c.scene.street.near_traffic; }, street));
  auto corridor = [](const ScenarioConfig& c) { return isKind(c, "corridor"); };
  t.push_back(real(
      "corridor_half_width", "m", closed(0.5, 20), "wall-to-centre distance",
      [](ScenarioConfig& c) -> double& { return c.scene.corridor.half_width; }, corridor));
  t.push_back(real(
      "corridor_height", "m", closed(1.5, 20), "floor to ceiling",
      [](ScenarioConfig& c) -> double& { return c.scene.corridor.height; }, corridor));
  t.push_back(integer(
      "corridor_pedestrians", 0, 100, "people walking along the corridor",
      [](ScenarioConfig& c) -> int& { return c.scene.corridor.pedestrians; }, corridor));
  t.push_back(real(
      "corridor_pedestrian_offset", "m", nonNegative(), "|y| of the people's paths",
      [](ScenarioConfig& c) -> double& { return c.scene.corridor.pedestrian_offset; }, corridor));
  auto tunnel = [](const ScenarioConfig& c) { return isKind(c, "tunnel"); };
  t.push_back(real(
      "tunnel_half_width", "m", closed(0.5, 50), "wall-to-centre distance",
      [](ScenarioConfig& c) -> double& { return c.scene.tunnel.half_width; }, tunnel));
  t.push_back(real(
      "tunnel_height", "m", closed(1.5, 50), "floor to ceiling",
      [](ScenarioConfig& c) -> double& { return c.scene.tunnel.height; }, tunnel));
  t.push_back(real(
      "tunnel_features_per_100m", "-", closed(0, 200),
      "lights, niches and signs per 100 m (0: featureless)",
      [](ScenarioConfig& c) -> double& { return c.scene.tunnel.features_per_100m; }, tunnel));
  auto open_area = [](const ScenarioConfig& c) { return isKind(c, "open"); };
  t.push_back(integer(
      "open_pedestrians", 0, 100, "people walking at |y| 8-14 m",
      [](ScenarioConfig& c) -> int& { return c.scene.open.pedestrians; }, open_area));
  auto parking = [](const ScenarioConfig& c) { return isKind(c, "parking"); };
  t.push_back(real(
      "parking_aisle_half_width", "m", closed(1.5, 20), "free half width of the aisle",
      [](ScenarioConfig& c) -> double& { return c.scene.parking.aisle_half_width; }, parking));
  t.push_back(real(
      "parking_occupancy", "-", closed(0, 1), "share of occupied bays",
      [](ScenarioConfig& c) -> double& { return c.scene.parking.occupancy; }, parking));
  t.push_back(integer(
      "parking_pedestrians", 0, 100, "people walking along the aisle",
      [](ScenarioConfig& c) -> int& { return c.scene.parking.pedestrians; }, parking));
  t.push_back(integer(
      "parking_moving_cars", 0, 100, "cars driving in the parallel aisles",
      [](ScenarioConfig& c) -> int& { return c.scene.parking.moving_cars; }, parking));
  {
    ScenarioKey k;
    k.name = "objects";
    k.unit = "-";
    k.range = "[0, 10000], whole";
    k.doc = "number of explicitly placed objects (object_1 ...); new ones must be given";
    k.format = [](const ScenarioConfig& c, int) { return std::to_string(c.scene.objects.size()); };
    k.parse = [](const Text& s, ScenarioConfig& c, int) {
      const auto n = toInteger<long>(s);
      if (n < 0 || n > 10000) throw std::invalid_argument("must be in [0, 10000]");
      c.scene.objects.resize(static_cast<std::size_t>(n));
    };
    k.check = [](const ScenarioConfig&, int) { return Text(); };
    k.applies = always;
    t.push_back(k);
  }
  {
    ScenarioKey k;
    k.name = "object_<k>";
    k.unit = "m, rad, m/s";
    k.range = "box|cylinder label cx cy cz hx hy hz yaw vx vy vz reflectivity";
    k.doc = "k-th object at t0 in the path frame (cylinder: hx = radius, hz = half height)";
    k.indexed = true;
    k.format = [](const ScenarioConfig& c, int i) {
      return objectText(c.scene.objects[static_cast<std::size_t>(i - 1)]);
    };
    k.parse = [](const Text& s, ScenarioConfig& c, int i) {
      if (i < 1 || static_cast<std::size_t>(i) > c.scene.objects.size())
        throw std::invalid_argument("beyond objects = " + std::to_string(c.scene.objects.size()));
      c.scene.objects[static_cast<std::size_t>(i - 1)] = toObject(s);
    };
    k.check = [](const ScenarioConfig& c, int i) {
      const SceneObject& o = c.scene.objects[static_cast<std::size_t>(i - 1)];
      if (!(o.half_size.minCoeff() > 0)) return Text("half sizes must be > 0");
      if (!(o.reflectivity >= 0 && o.reflectivity <= 1))
        return Text("reflectivity must be in [0, 1]");
      if (o.label.empty() || o.label.find_first_not_of("abcdefghijklmnopqrstuvwxyz_") != Text::npos)
        return Text("label must be a word of a-z and _");
      return Text();
    };
    k.applies = always;
    t.push_back(k);
  }
  // LiDAR.
  t.push_back(integer("points_per_frame", 0, 10000000, "rays per frame (misses are dropped)",
                      [](ScenarioConfig& c) -> int& { return c.points_per_frame; }));
  t.push_back(integer("lines", 1, 65535, "scan lines per frame",
                      [](ScenarioConfig& c) -> int& { return c.lines; }));
  t.push_back(real("frame_rate", "Hz", positive(), "frames per second",
                   [](ScenarioConfig& c) -> double& { return c.frame_rate; }));
  t.push_back(real("hfov_deg", "deg", open(0, 180), "horizontal field of view",
                   [](ScenarioConfig& c) -> double& { return c.hfov_deg; }));
  t.push_back(real("vfov_deg", "deg", open(0, 180), "vertical field of view",
                   [](ScenarioConfig& c) -> double& { return c.vfov_deg; }));
  t.push_back(choice<LineOrder>("line_order", "order in which the lines of a frame are measured",
                                {{"top_down", LineOrder::TopDown},
                                 {"bottom_up", LineOrder::BottomUp},
                                 {"interleaved", LineOrder::Interleaved}},
                                [](ScenarioConfig& c) -> LineOrder& { return c.line_order; }));
  t.push_back(choice<LineDirection>(
      "line_direction", "azimuth sweep: back and forth, or every line the same way",
      {{"alternating", LineDirection::Alternating}, {"forward", LineDirection::Forward}},
      [](ScenarioConfig& c) -> LineDirection& { return c.line_direction; }));
  t.push_back(real("min_range", "m", nonNegative(), "closer returns are dropped",
                   [](ScenarioConfig& c) -> double& { return c.min_range; }));
  t.push_back(real("max_range", "m", positive(), "farther returns are dropped; > min_range",
                   [](ScenarioConfig& c) -> double& { return c.max_range; }));
  t.push_back(real("range_sigma", "m", nonNegative(), "range noise std",
                   [](ScenarioConfig& c) -> double& { return c.range_sigma; }));
  t.push_back(real("doppler_sigma", "m/s", nonNegative(), "Doppler noise std",
                   [](ScenarioConfig& c) -> double& { return c.doppler_sigma; }));
  t.push_back(real("outlier_ratio", "-", closed(0, 1), "share of points with a gross Doppler error",
                   [](ScenarioConfig& c) -> double& { return c.outlier_ratio; }));
  // IMU.
  t.push_back(real("imu_rate", "Hz", positive(), "IMU samples per second",
                   [](ScenarioConfig& c) -> double& { return c.imu_rate; }));
  t.push_back(real("gyro_sigma", "rad/s", nonNegative(), "gyro white noise per sample (datasheet)",
                   [](ScenarioConfig& c) -> double& { return c.gyro_sigma; }));
  t.push_back(real("accel_sigma", "m/s^2", nonNegative(),
                   "accelerometer white noise per sample (datasheet)",
                   [](ScenarioConfig& c) -> double& { return c.accel_sigma; }));
  t.push_back(vec3("gyro_sigma_scale", "-", nonNegative(),
                   "this unit's per-axis sigma / gyro_sigma",
                   [](ScenarioConfig& c) -> Vec3& { return c.gyro_sigma_scale; }));
  t.push_back(vec3("accel_sigma_scale", "-", nonNegative(),
                   "this unit's per-axis sigma / accel_sigma",
                   [](ScenarioConfig& c) -> Vec3& { return c.accel_sigma_scale; }));
  t.push_back(flag("random_biases", "draw the biases with the seed (the presets' ranges)",
                   [](ScenarioConfig& c) -> bool& { return c.random_biases; }));
  auto fixed_biases = [](const ScenarioConfig& c) { return !c.random_biases; };
  t.push_back(vec3(
      "b_g", "rad/s", any(), "constant gyro bias (random_biases false)",
      [](ScenarioConfig& c) -> Vec3& { return c.b_g; }, fixed_biases));
  t.push_back(vec3(
      "b_a", "m/s^2", any(), "constant accelerometer bias (random_biases false)",
      [](ScenarioConfig& c) -> Vec3& { return c.b_a; }, fixed_biases));
  // Calibration: the truth, and what is declared.
  t.push_back(vec3("lidar_rpy_deg", "deg", any(), "true R_bl = Rz(yaw) Ry(pitch) Rx(roll)",
                   [](ScenarioConfig& c) -> Vec3& { return c.lidar_rpy_deg; }));
  t.push_back(vec3("lidar_position", "m", any(), "true p_bl",
                   [](ScenarioConfig& c) -> Vec3& { return c.lidar_position; }));
  t.push_back(real("lidar_rpy_jitter_deg", "deg", nonNegative(),
                   "seeded uniform perturbation of each angle, +-",
                   [](ScenarioConfig& c) -> double& { return c.lidar_rpy_jitter_deg; }));
  t.push_back(real("lidar_position_jitter", "m", nonNegative(),
                   "seeded uniform perturbation of each p_bl axis, +-",
                   [](ScenarioConfig& c) -> double& { return c.lidar_position_jitter; }));
  t.push_back(vec3("declared_rotation_error_deg", "deg", any(),
                   "declared R_bl = true R_bl Exp(this rotation vector)",
                   [](ScenarioConfig& c) -> Vec3& { return c.declared_rotation_error_deg; }));
  t.push_back(vec3("declared_position_error", "m", any(), "declared p_bl = true p_bl + this",
                   [](ScenarioConfig& c) -> Vec3& { return c.declared_position_error; }));
  t.push_back(real("lidar_time_offset", "s", closed(-1, 1),
                   "LiDAR clock minus IMU clock: LiDAR stamps = true time + this",
                   [](ScenarioConfig& c) -> double& { return c.lidar_time_offset; }));
  return t;
}

/// object_<k> keys: the index k >= 1, or 0 when the name is not one.
int objectIndex(const Text& name) {
  const Text prefix = "object_";
  if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) return 0;
  const Text digits = name.substr(prefix.size());
  if (digits.find_first_not_of("0123456789") != Text::npos || digits[0] == '0') return 0;
  try {
    const long k = std::stol(digits);
    return k <= 10000 ? static_cast<int>(k) : 0;
  } catch (const std::exception&) {
    return 0;
  }
}

[[noreturn]] void fail(const Text& key, const Text& why) {
  throw std::invalid_argument(key + ": " + why);
}

}  // namespace

const std::vector<ScenarioKey>& scenarioKeys() {
  static const std::vector<ScenarioKey> kTable = buildTable();  // immutable after construction
  return kTable;
}

std::string scenarioKeysHelp() {
  const ScenarioConfig defaults;
  std::ostringstream o;
  o << "[scenario] keys (default: preset dyna_01, seed 1)\n";
  for (const ScenarioKey& k : scenarioKeys()) {
    o << k.name;
    if (!k.unit.empty()) o << " [" << k.unit << "]";
    if (!k.indexed) o << " = " << k.format(defaults, 0);
    o << "  (" << k.range << ")  " << k.doc << "\n";
  }
  return o.str();
}

void validateScenario(const ScenarioConfig& c) {
  for (const ScenarioKey& k : scenarioKeys()) {
    if (k.indexed) {
      for (std::size_t i = 1; i <= c.scene.objects.size(); ++i) {
        const Text why = k.check(c, static_cast<int>(i));
        if (!why.empty()) fail("object_" + std::to_string(i), why);
      }
      continue;
    }
    const Text why = k.check(c, 0);
    if (!why.empty()) fail(k.name, why);
  }
  if (!(c.max_range > c.min_range)) fail("max_range", "must be > min_range");
  if (!c.scene.auto_extent && !(c.scene.x_max > c.scene.x_min))
    fail("scene_x_max", "must be > scene_x_min");
  for (const ScalarSignal* s : {&c.motion.pos[0], &c.motion.pos[1], &c.motion.pos[2],
                                &c.motion.rpy[0], &c.motion.rpy[1], &c.motion.rpy[2]}) {
    for (double p : s->poly)
      if (!std::isfinite(p)) fail("motion", "polynomial coefficients must be finite");
    for (const Sinusoid& w : s->waves)
      if (!std::isfinite(w.amplitude) || !std::isfinite(w.phase))
        fail("motion", "wave amplitudes and phases must be finite");
  }
}

ScenarioConfig scenarioFromKeys(const ScenarioKeyValues& section, const ScenarioBase& base) {
  std::map<Text, Text> given;
  std::map<int, Text> objects;
  for (const auto& [raw_key, value] : section) {
    const Text key = trim(raw_key);
    if (given.count(key) || objects.count(objectIndex(key))) fail(key, "given twice");
    if (const int i = objectIndex(key)) {
      objects[i] = value;
      continue;
    }
    const auto& keys = scenarioKeys();
    const bool known = std::any_of(keys.begin(), keys.end(), [&](const ScenarioKey& k) {
      return !k.indexed && k.name == key;
    });
    if (!known) fail(key, "unknown key");
    given[key] = value;
  }
  // The base.
  const Text name = given.count("preset") ? trim(given["preset"]) : base.preset;
  std::uint64_t seed = base.seed;
  ScenarioConfig c;
  try {
    if (given.count("seed")) seed = toInteger<std::uint64_t>(given["seed"]);
  } catch (const std::invalid_argument& e) {
    fail("seed", e.what());
  }
  try {
    c = name == "random" ? randomScenario(seed) : preset(name, seed);
  } catch (const std::invalid_argument& e) {
    fail("preset", e.what());
  }
  const std::size_t base_objects = c.scene.objects.size();
  // Every other key over it, in table order (objects before object_<k>).
  for (const ScenarioKey& k : scenarioKeys()) {
    if (k.name == "preset" || k.name == "seed") continue;
    if (k.indexed) {
      for (const auto& [i, value] : objects) {
        try {
          k.parse(value, c, i);
        } catch (const std::invalid_argument& e) {
          fail("object_" + std::to_string(i), e.what());
        }
      }
      for (std::size_t i = base_objects + 1; i <= c.scene.objects.size(); ++i)
        if (!objects.count(static_cast<int>(i)))
          fail("object_" + std::to_string(i),
               "missing (objects = " + std::to_string(c.scene.objects.size()) + ")");
      continue;
    }
    const auto it = given.find(k.name);
    if (it == given.end()) continue;
    try {
      k.parse(it->second, c, 0);
    } catch (const std::invalid_argument& e) {
      fail(k.name, e.what());
    }
  }
  if ((given.count("b_g") || given.count("b_a")) && !given.count("random_biases"))
    c.random_biases = false;
  validateScenario(c);
  return c;
}

std::string scenarioIni(const ScenarioConfig& c, const std::vector<std::string>& comments) {
  std::ostringstream o;
  for (const std::string& line : comments) o << "; " << line << "\n";
  o << "[scenario]\n";
  for (const ScenarioKey& k : scenarioKeys()) {
    if (!k.applies(c)) continue;
    if (k.indexed) {
      for (std::size_t i = 1; i <= c.scene.objects.size(); ++i)
        o << "object_" << i << " = " << k.format(c, static_cast<int>(i)) << "\n";
      continue;
    }
    o << k.name << " = " << k.format(c, 0) << "\n";
  }
  return o.str();
}

void writeScenarioIni(const std::string& path, const ScenarioConfig& config,
                      const std::vector<std::string>& comments) {
  const std::string text = scenarioIni(config, comments);
  writeFileAtomically(path, [&](std::ostream& out) { out << text; });
}

ScenarioKeyValues readScenarioIniText(const std::string& text) {
  ScenarioKeyValues out;
  std::istringstream is(text);
  Text section;
  int n = 0;
  for (Text line; std::getline(is, line);) {
    ++n;
    const Text s = trim(line);
    if (s.empty() || s[0] == ';' || s[0] == '#') continue;
    if (s.front() == '[') {
      if (s.back() != ']')
        throw std::invalid_argument("line " + std::to_string(n) + ": bad section");
      section = trim(s.substr(1, s.size() - 2));
      continue;
    }
    const auto eq = s.find('=');
    if (eq == Text::npos)
      throw std::invalid_argument("line " + std::to_string(n) + ": expected key = value");
    if (section == "scenario") out.emplace_back(trim(s.substr(0, eq)), trim(s.substr(eq + 1)));
  }
  return out;
}

}  // namespace freeinit::sim
