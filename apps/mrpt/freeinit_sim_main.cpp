// freeinit-sim: writes a simulated preset or random scenario as a rawlog plus its ground truth.
#include <freeinit/mrpt_plugins/command_line.h>
#include <freeinit/mrpt_plugins/sim_app.h>
#include <freeinit/sim/simulator.h>

#include <cstdint>
#include <iostream>
#include <stdexcept>

int main(int argc, char** argv) {
  namespace plugins = freeinit::mrpt_plugins;
  namespace config = freeinit::config;
  plugins::CommandLine cli("freeinit-sim",
                           "Doppler LiDAR + IMU recording with ground truth, as a rawlog");
  const auto& preset =
      cli.choice("p", "preset", "simulator preset", "dyna_01", freeinit::sim::presetNames());
  const auto& seed = cli.integer("s", "seed", "random seed", 1, 0, 4294967295LL, "N");
  const auto& random = cli.integer("", "random",
                                   "simulate the randomized scenario drawn with this seed "
                                   "(instead of a preset)",
                                   0, 0, 4294967295LL, "SEED");
  const auto& duration =
      cli.number("d", "duration", "seconds (0: the preset's)", 0, config::between(0, 3600), "S");
  const auto& points = cli.integer("n", "points-per-frame", "points per frame (0: the preset's)", 0,
                                   0, 10000000, "N");
  const auto& out = cli.text("o", "out", "output rawlog; truth files go beside it", "", "FILE",
                             "<preset>.rawlog");
  const auto& scenario = cli.text("c", "scenario",
                                  "INI file with a [scenario] section (a base preset or random "
                                  "+ scenario keys, or a written <out>.scenario.ini)",
                                  "", "FILE", "none");
  const auto& keys = cli.flag("", "scenario-keys", "print the [scenario] keys and exit");
  const auto& in_g = cli.flag("", "accel-in-g", "write accelerations in g");
  if (const auto code = cli.parse(argc, argv)) return *code;
  return plugins::runMain(cli.program(), [&] {
    if (keys.value) {
      std::cout << plugins::SimApp::scenarioKeys();
      return 0;
    }
    if (random.given && (seed.given || preset.given || scenario.given))
      throw std::invalid_argument("--random: not with --seed, --preset or --scenario");
    plugins::SimApp app;
    app.params.preset = preset.value;
    app.params.seed = static_cast<std::uint64_t>(random.given ? random.value : seed.value);
    app.params.random = random.given;
    app.params.duration = duration.value;
    app.params.points_per_frame = static_cast<int>(points.value);
    const std::string base = random.given ? "random_" + std::to_string(random.value) : preset.value;
    app.params.output = out.given ? out.value : base + ".rawlog";
    app.params.accel_in_g = in_g.value;
    app.params.scenario_file = scenario.value;
    app.run(std::cout);
    return 0;
  });
}
