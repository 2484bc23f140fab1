// The scenario INI: a written file read back gives the same recording bit for bit (presets and
// random scenarios), the short form (a preset plus overrides) reads, and every bad section, key
// or value is named with its file and line.
#include <freeinit/io/ini_file.h>
#include <freeinit/sim/random_scenario.h>
#include <freeinit/sim/scenario_ini.h>
#include <freeinit/sim/simulator.h>
#include <gtest/gtest.h>

#include <set>
#include <stdexcept>
#include <string>

#include "test_sim_recording_hash.h"

namespace freeinit::sim {
namespace {

/// The config read back from its written INI, over a base that differs from it in every way.
ScenarioConfig roundTrip(const ScenarioConfig& c) {
  return scenarioFromIni(config::IniFile::parse(scenarioIni(c, {"written"}), "written.ini"),
                         ScenarioBase{"tunnel_vehicular", 99});
}

void expectSameRecording(const ScenarioConfig& c) {
  const ScenarioConfig back = roundTrip(c);
  EXPECT_EQ(scenarioIni(back), scenarioIni(c)) << c.name << " " << c.seed;
  const Recording a = simulate(c), b = simulate(back);
  ASSERT_GT(a.frames.size(), 0u);
  EXPECT_EQ(test::firstDifference(a, b), "") << c.name << " seed " << c.seed;
}

TEST(SimScenarioIni, RoundTripIsBitExactForEveryPreset) {
  for (const std::string& name : presetNames()) {
    ScenarioConfig c = preset(name, 3);
    c.duration = 0.3;
    c.points_per_frame = 2000;
    expectSameRecording(c);
  }
}

TEST(SimScenarioIni, RoundTripIsBitExactForRandomScenarios) {
  // Seeds 1-4 plus the first with a wrong calibration including a clock offset, the first of every
  // scene kind and line order (each exercises its own keys).
  std::set<std::uint64_t> seeds = {1, 2, 3, 4};
  std::set<std::string> kinds, orders;
  bool offset = false;
  for (std::uint64_t s = 1; s < 200; ++s) {
    const RandomScenario r = drawRandomScenario(s);
    if (!offset && r.info.lidar_time_offset != 0) {
      offset = true;
      seeds.insert(s);
    }
    if (kinds.insert(r.info.scene).second) seeds.insert(s);
    if (orders.insert(std::to_string(static_cast<int>(r.config.line_order))).second)
      seeds.insert(s);
  }
  ASSERT_TRUE(offset);
  EXPECT_EQ(kinds.size(), 5u);
  EXPECT_EQ(orders.size(), 3u);
  for (std::uint64_t s : seeds) {
    ScenarioConfig c = randomScenario(s);
    c.duration = 0.35;
    c.points_per_frame = std::min(c.points_per_frame, 4000);
    expectSameRecording(c);
  }
}

// The short form of a scenario file: a base preset, a seed and a few overrides.
TEST(SimScenarioIni, ShortFormOverridesItsBasePreset) {
  const ScenarioConfig c = scenarioFromKeys({{"preset", "stat_01"},
                                             {"seed", "7"},
                                             {"duration", "0.5"},
                                             {"imu_rate", "100"},
                                             {"b_g", "0.01 -0.02 0.003"}});
  ScenarioConfig expected = preset("stat_01", 7);
  expected.duration = 0.5;
  expected.imu_rate = 100;
  expected.b_g = Vec3(0.01, -0.02, 0.003);
  expected.random_biases = false;  // b_g given without random_biases
  EXPECT_EQ(scenarioIni(c), scenarioIni(expected));
  // No preset key: the caller's base; `random` draws randomScenario(seed).
  EXPECT_EQ(scenarioIni(scenarioFromKeys({}, {"dyna_04", 2})), scenarioIni(preset("dyna_04", 2)));
  EXPECT_EQ(scenarioIni(scenarioFromKeys({{"preset", "random"}, {"seed", "12"}})),
            scenarioIni(randomScenario(12)));
  const ScenarioConfig kept =
      scenarioFromKeys({{"preset", "stat_01"}, {"b_a", "0 0 0.1"}, {"random_biases", "true"}});
  EXPECT_TRUE(kept.random_biases);
}

std::string errorOf(const std::string& text) {
  try {
    scenarioFromIni(config::IniFile::parse(text, "s.ini"));
  } catch (const config::ConfigError& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("not a ConfigError: ") + e.what();
  }
  return "no error";
}

std::string errorOf(const ScenarioKeyValues& kv) {
  std::string text = "[scenario]\n";
  for (const auto& [k, v] : kv) text += k + " = " + v + "\n";
  return errorOf(text);
}

TEST(SimScenarioIni, BadSectionsKeysAndValuesAreNamedWithTheirLine) {
  EXPECT_EQ(errorOf({{"imu_rat", "100"}}),
            "s.ini:2: [scenario] imu_rat: unknown key (did you mean imu_rate?)");
  EXPECT_EQ(errorOf({{"duration", "1"}, {"duration", "2"}}),
            "s.ini:3: [scenario] duration: key given twice (first at line 2)");
  EXPECT_EQ(errorOf({{"duration", "-1"}}),
            "s.ini:2: [scenario] duration: -1 is out of range: accepted > 0 s");
  EXPECT_EQ(errorOf({{"duration", "1s"}}), "s.ini:2: [scenario] duration: '1s' is not a number");
  EXPECT_EQ(errorOf({{"outlier_ratio", "1.5"}}),
            "s.ini:2: [scenario] outlier_ratio: 1.5 is out of range: accepted [0, 1]");
  EXPECT_EQ(errorOf({{"b_g", "1 2"}}),
            "s.ini:2: [scenario] b_g: expected 3 numbers separated by blanks, got 2");
  EXPECT_EQ(errorOf({{"lines", "2.5"}}), "s.ini:2: [scenario] lines: '2.5' is not a whole number");
  EXPECT_EQ(errorOf({{"lines", "0"}}),
            "s.ini:2: [scenario] lines: 0 is out of range: accepted [1, 65535]");
  EXPECT_EQ(errorOf({{"line_order", "spiral"}}),
            "s.ini:2: [scenario] line_order: 'spiral' is not one of 'top_down', 'bottom_up', "
            "'interleaved'");
  EXPECT_EQ(errorOf({{"scene", "moon"}}),
            "s.ini:2: [scenario] scene: 'moon' is not one of 'street', 'corridor', 'tunnel', "
            "'open', 'parking'");
  EXPECT_EQ(errorOf({{"min_range", "5"}, {"max_range", "4"}}),
            "s.ini:3: [scenario] max_range: must be > min_range");
  EXPECT_EQ(
      errorOf({{"preset", "nope"}}).rfind("s.ini:2: [scenario] preset: 'nope' is not one of '", 0),
      0u);
  EXPECT_NE(errorOf({{"preset", "nope"}}).find("'stat_01'"), std::string::npos);
  EXPECT_NE(errorOf({{"preset", "nope"}}).find("'random'"), std::string::npos);
  EXPECT_EQ(errorOf({{"seed", "-1"}}).rfind("s.ini:2: [scenario] seed: '-1' is out of range", 0),
            0u);
  EXPECT_EQ(errorOf({{"random_biases", "maybe"}}),
            "s.ini:2: [scenario] random_biases: 'maybe' is not a boolean (true/false)");
  EXPECT_EQ(errorOf({{"objects", "1"}}), "s.ini:1: [scenario] object_1: missing (objects = 1)");
  EXPECT_EQ(errorOf({{"objects", "1001"}}),
            "s.ini:2: [scenario] objects: '1001' is out of range for this key (0 to 1000)");
  EXPECT_EQ(errorOf({{"object_1", "box car 0 0 1 2 1 1 0 5 0 0 0.5"}}),
            "s.ini:2: [scenario] object_1: beyond objects = 0");
  EXPECT_EQ(errorOf({{"objects", "1"}, {"object_1", "sphere car 0 0 1 2 1 1 0 5 0 0 0.5"}}),
            "s.ini:3: [scenario] object_1: shape must be box or cylinder, got 'sphere'");
  EXPECT_EQ(errorOf({{"objects", "1"}, {"object_1", "box car 0 0 1 2 0 1 0 5 0 0 0.5"}}),
            "s.ini:3: [scenario] object_1: half sizes must be > 0");
  EXPECT_EQ(errorOf({{"object_01", "box car 0 0 1 2 1 1 0 5 0 0 0.5"}}),
            "s.ini:2: [scenario] object_01: unknown key (did you mean objects?)");
  EXPECT_EQ(errorOf({{"x_waves", "0.1 1"}}),
            "s.ini:2: [scenario] x_waves: expected 'amplitude freq_hz phase', got '0.1 1'");
  EXPECT_EQ(errorOf({{"x_waves", "0.1 -1 0"}}),
            "s.ini:2: [scenario] x_waves: frequencies must be >= 0");
  EXPECT_EQ(errorOf({{"scene_auto_extent", "false"}, {"scene_x_min", "5"}, {"scene_x_max", "5"}}),
            "s.ini:4: [scenario] scene_x_max: must be > scene_x_min");
  EXPECT_EQ(errorOf({{"t0", "${T0}"}}).rfind("s.ini:2: [scenario] t0: '${T0}': variables", 0), 0u);
  EXPECT_EQ(errorOf("[scenario]\nduration = 1\n[scenaro]\n"),
            "s.ini:3: [scenaro]: unknown section (did you mean [scenario]?); expected [scenario]");
  EXPECT_EQ(errorOf("; nothing\n"), "s.ini: no [scenario] section");
  // The same checks guard configs built in code.
  ScenarioConfig c = preset("dyna_01");
  c.hfov_deg = 180;
  try {
    simulate(c);
    FAIL() << "accepted hfov_deg = 180";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()),
              "freeinit::sim::simulate: configuration key scenario.hfov_deg: 180 is out of range: "
              "accepted (0, 180) deg");
  }
  c = preset("dyna_01");
  c.scene.objects.push_back(SceneObject{});
  c.scene.objects.back().label = "Car";
  EXPECT_THROW(validateScenario(c), config::ConfigError);
}

// Objects given in a file join the scene, whatever the order of their keys.
TEST(SimScenarioIni, ObjectsJoinTheScene) {
  const std::string text =
      "; a person walking through the view\n[scenario]\npreset = stat_02\n"
      "object_1 = cylinder person 6 -8.2 0.85 0.3 0.3 0.85 0 0 1.2 0 0.5 ; before objects\n"
      "# comment\nobjects = 1\n";
  const ScenarioConfig c = scenarioFromIni(config::IniFile::parse(text, "objects.ini"));
  ASSERT_EQ(c.scene.objects.size(), 1u);
  EXPECT_EQ(c.scene.objects[0].shape, ObjectShape::Cylinder);
  EXPECT_EQ(c.scene.objects[0].velocity, Vec3(0, 1.2, 0));
  const auto scene = makeScene(c, *makeTrajectory(c));
  const Primitive& p = scene->primitives().back();
  EXPECT_LT((p.centerAt(1.0) - Vec3(6, -7.0, 0.85)).norm(), 1e-12);
  EXPECT_NE(scenarioIni(c).find("\nobjects "), std::string::npos);
  EXPECT_NE(scenarioIni(c).find("\nobject_1 "), std::string::npos);
}

// Every key: documented, and its default (dyna_01's value) reads back as itself; the help lists
// each with its unit, default and accepted values.
TEST(SimScenarioIni, KeyTableIsCompleteAndConsistent) {
  const ScenarioConfig defaults;
  EXPECT_EQ(scenarioIni(defaults), scenarioIni(preset("dyna_01", 1)));
  EXPECT_NO_THROW(validateScenario(defaults));
  const auto& section = scenarioSection();
  const std::string help = scenarioKeysHelp();
  std::set<std::string> names;
  for (const config::KeyInfo& k : section.keys()) {
    EXPECT_TRUE(names.insert(k.name).second) << k.name;
    EXPECT_FALSE(k.doc.empty()) << k.name;
    EXPECT_FALSE(k.unit.empty()) << k.name;
    EXPECT_FALSE(k.accepted.empty()) << k.name;
    EXPECT_NE(help.find("\n" + k.name + " [" + k.unit + "]"), std::string::npos) << k.name;
    if (k.name == "object_<k>") continue;
    std::string error;
    EXPECT_EQ(section.canonical(k.name, k.default_value, error), k.default_value) << k.name;
    EXPECT_EQ(error, "") << k.name;
    EXPECT_NE(
        help.find(k.name + " [" + k.unit + "] = " + k.default_value + "  (" + k.accepted + ")"),
        std::string::npos)
        << k.name;
  }
  EXPECT_NE(help.find("lidar_time_offset [s] = 0  ([-1, 1])"), std::string::npos);
  EXPECT_NE(help.find("object_<k> [m, rad, m/s]  (box|cylinder"), std::string::npos);
}

}  // namespace
}  // namespace freeinit::sim
