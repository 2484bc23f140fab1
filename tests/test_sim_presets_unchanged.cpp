// The presets mirror the paper and the published Results: their recordings must stay exactly what
// they were when the scenario description became explicit (same seeds, same numbers). The digests
// below were computed with the simulator before that change, on this toolchain (GCC, glibc libm,
// Release); a different libm may round sin/cos differently and then needs new reference digests.
#include <freeinit/sim/simulator.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <map>
#include <string>

#include "test_sim_recording_hash.h"

namespace freeinit::sim {
namespace {

// 0.3 s, 4000 points per frame, seed 3: every preset's motion, scene, noise and biases.
TEST(SimPresetsUnchanged, ShortRecordingsOfEveryPreset) {
  const std::map<std::string, std::uint64_t> expected = {
      {"dyna_01", 0x21d4916e9de169b8ull},          {"dyna_02", 0xf5d1815f91e1b005ull},
      {"dyna_03", 0x18f8c01ae71108c9ull},          {"dyna_04", 0xfecc32cc0a9ae706ull},
      {"dyna_05", 0x89c1001b55d659b8ull},          {"dyna_06", 0xd43b86d4b522aee6ull},
      {"stat_01", 0x904d5e1df7ec71c4ull},          {"stat_02", 0x3b1da7e2c81203caull},
      {"stat_03", 0xcbaf07bc7ef21813ull},          {"stat_04", 0xa098ff551ddc38bbull},
      {"tunnel_handheld", 0x5cad5c9108623e7aull},  {"tunnel_wheeled", 0xeee41ed01e42189bull},
      {"tunnel_vehicular", 0x1470211b003e0337ull},
  };
  ASSERT_EQ(presetNames().size(), expected.size());
  for (const std::string& name : presetNames()) {
    ScenarioConfig c = preset(name, 3);
    c.duration = 0.3;
    c.points_per_frame = 4000;
    EXPECT_EQ(test::recordingDigest(simulate(c)), expected.at(name)) << name;
  }
}

// The full 5 s of every preset (its scene is sized by the duration), 300 points per frame, seed 5.
TEST(SimPresetsUnchanged, FullLengthScenesOfEveryPreset) {
  const std::map<std::string, std::uint64_t> expected = {
      {"dyna_01", 0xc59dd51212daffc3ull},          {"dyna_02", 0x6d57e6f86af9388full},
      {"dyna_03", 0x50b5ef2d8320905cull},          {"dyna_04", 0x3a9e2ce752fad9fbull},
      {"dyna_05", 0xbadca7ee3e92233eull},          {"dyna_06", 0x64a864fe46fdf2f4ull},
      {"stat_01", 0x216e446d04e31619ull},          {"stat_02", 0x8d15836944fe2055ull},
      {"stat_03", 0xf2626d111f2c7d06ull},          {"stat_04", 0x340b0d3e9e82834bull},
      {"tunnel_handheld", 0xb5813a5707a9911full},  {"tunnel_wheeled", 0x516036cdd94ce13cull},
      {"tunnel_vehicular", 0x70f8bc2e6864b282ull},
  };
  for (const std::string& name : presetNames()) {
    ScenarioConfig c = preset(name, 5);
    c.points_per_frame = 300;
    EXPECT_EQ(test::recordingDigest(simulate(c)), expected.at(name)) << name;
  }
}

// The default density (60,000 points per frame) of dyna_01 and stat_01, 0.25 s, seed 1.
TEST(SimPresetsUnchanged, DefaultDensity) {
  for (const auto& [name, digest] : std::map<std::string, std::uint64_t>{
           {"dyna_01", 0xbf31b668170c0f3dull}, {"stat_01", 0x917e9bd3e79dd0feull}}) {
    ScenarioConfig c = preset(name, 1);
    c.duration = 0.25;
    EXPECT_EQ(test::recordingDigest(simulate(c)), digest) << name;
  }
}

}  // namespace
}  // namespace freeinit::sim
