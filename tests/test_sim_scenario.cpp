// The scenario INI: a written file read back gives the same recording bit for bit (presets and
// random scenarios), today's short form (a preset plus overrides) still reads, and every bad key
// or value is named.
#include <freeinit/sim/random_scenario.h>
#include <freeinit/sim/scenario_ini.h>
#include <gtest/gtest.h>

#include <set>
#include <stdexcept>
#include <string>

#include "test_sim_recording_hash.h"

namespace freeinit::sim {
namespace {

/// The config read back from its written INI, over a base that differs from it in every way.
ScenarioConfig roundTrip(const ScenarioConfig& c) {
  return scenarioFromKeys(readScenarioIniText(scenarioIni(c)),
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

std::string errorOf(const ScenarioKeyValues& kv) {
  try {
    scenarioFromKeys(kv);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "no error";
}

TEST(SimScenarioIni, BadKeysAndValuesAreNamed) {
  EXPECT_EQ(errorOf({{"imu_rat", "100"}}), "imu_rat: unknown key");
  EXPECT_EQ(errorOf({{"duration", "1"}, {"duration", "2"}}), "duration: given twice");
  EXPECT_EQ(errorOf({{"duration", "-1"}}), "duration: must be > 0");
  EXPECT_EQ(errorOf({{"duration", "1s"}}), "duration: expected a number, got '1s'");
  EXPECT_EQ(errorOf({{"outlier_ratio", "1.5"}}), "outlier_ratio: must be in [0, 1]");
  EXPECT_EQ(errorOf({{"b_g", "1 2"}}), "b_g: expected 3 numbers, got '1 2'");
  EXPECT_EQ(errorOf({{"lines", "2.5"}}), "lines: expected a whole number, got '2.5'");
  EXPECT_EQ(errorOf({{"line_order", "spiral"}}),
            "line_order: expected one of top_down|bottom_up|interleaved, got 'spiral'");
  EXPECT_EQ(errorOf({{"scene", "moon"}}),
            "scene: must be one of street|corridor|tunnel|open|parking");
  EXPECT_EQ(errorOf({{"min_range", "5"}, {"max_range", "4"}}), "max_range: must be > min_range");
  EXPECT_EQ(errorOf({{"preset", "nope"}}).rfind("preset: ", 0), 0u);
  EXPECT_EQ(errorOf({{"random_biases", "maybe"}}),
            "random_biases: expected true or false, got 'maybe'");
  EXPECT_EQ(errorOf({{"objects", "1"}}), "object_1: missing (objects = 1)");
  EXPECT_EQ(errorOf({{"object_1", "box car 0 0 1 2 1 1 0 5 0 0 0.5"}}),
            "object_1: beyond objects = 0");
  EXPECT_EQ(errorOf({{"objects", "1"}, {"object_1", "sphere car 0 0 1 2 1 1 0 5 0 0 0.5"}}),
            "object_1: shape must be box or cylinder, got 'sphere'");
  EXPECT_EQ(errorOf({{"objects", "1"}, {"object_1", "box car 0 0 1 2 0 1 0 5 0 0 0.5"}}),
            "object_1: half sizes must be > 0");
  EXPECT_EQ(errorOf({{"x_waves", "0.1 1"}}), "x_waves: expected 3 numbers, got '0.1 1'");
  EXPECT_EQ(errorOf({{"scene_auto_extent", "false"}, {"scene_x_min", "5"}, {"scene_x_max", "5"}}),
            "scene_x_max: must be > scene_x_min");
  // The same checks guard configs built in code.
  ScenarioConfig c = preset("dyna_01");
  c.hfov_deg = 180;
  try {
    simulate(c);
    FAIL() << "accepted hfov_deg = 180";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "freeinit::sim::simulate: hfov_deg: must be in (0, 180)");
  }
}

// Objects given in a file join the scene; an INI with comments and other sections reads.
TEST(SimScenarioIni, ObjectsAndTheMinimalReader) {
  const std::string text =
      "; a person walking through the view\n[other]\nx = 1\n[scenario]\npreset = stat_02\n"
      "# comment\nobjects = 1\nobject_1 = cylinder person 6 -8.2 0.85 0.3 0.3 0.85 0 0 1.2 0 0.5\n";
  const ScenarioConfig c = scenarioFromKeys(readScenarioIniText(text));
  ASSERT_EQ(c.scene.objects.size(), 1u);
  EXPECT_EQ(c.scene.objects[0].shape, ObjectShape::Cylinder);
  EXPECT_EQ(c.scene.objects[0].velocity, Vec3(0, 1.2, 0));
  const auto scene = makeScene(c, *makeTrajectory(c));
  const Primitive& p = scene->primitives().back();
  EXPECT_LT((p.centerAt(1.0) - Vec3(6, -7.0, 0.85)).norm(), 1e-12);
  EXPECT_THROW(readScenarioIniText("[scenario]\nno equals sign\n"), std::invalid_argument);
}

// Every key: documented, and its default (dyna_01's value) reads back as itself.
TEST(SimScenarioIni, KeyTableIsCompleteAndConsistent) {
  const ScenarioConfig defaults;
  EXPECT_EQ(scenarioIni(defaults), scenarioIni(preset("dyna_01", 1)));
  std::set<std::string> names;
  for (const ScenarioKey& k : scenarioKeys()) {
    EXPECT_TRUE(names.insert(k.name).second) << k.name;
    EXPECT_FALSE(k.doc.empty()) << k.name;
    EXPECT_FALSE(k.range.empty()) << k.name;
    if (k.indexed) continue;
    ScenarioConfig c = defaults;
    k.parse(k.format(defaults, 0), c, 0);
    EXPECT_EQ(k.format(c, 0), k.format(defaults, 0)) << k.name;
    EXPECT_EQ(k.check(defaults, 0), "") << k.name;
  }
  EXPECT_NE(scenarioKeysHelp().find("lidar_time_offset [s] = 0"), std::string::npos);
}

}  // namespace
}  // namespace freeinit::sim
