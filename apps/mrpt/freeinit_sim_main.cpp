// freeinit-sim: writes a simulated preset or random scenario as a rawlog plus its ground truth.
#include <freeinit/mrpt/SimApp.h>
#include <mrpt/3rdparty/tclap/CmdLine.h>

#include <cstdint>
#include <iostream>
#include <stdexcept>

int main(int argc, char** argv) {
  try {
    TCLAP::CmdLine cmd("freeinit-sim: Doppler LiDAR + IMU recording with ground truth, as a rawlog",
                       ' ', "0.1");
    TCLAP::ValueArg<std::string> preset("p", "preset", "preset (dyna_01..06, stat_01..04, ...)",
                                        false, "dyna_01", "NAME", cmd);
    TCLAP::ValueArg<unsigned> seed("s", "seed", "random seed", false, 1, "N", cmd);
    TCLAP::ValueArg<std::uint64_t> random("", "random",
                                          "simulate the randomized scenario drawn with this seed "
                                          "(instead of a preset)",
                                          false, 0, "SEED", cmd);
    TCLAP::ValueArg<double> duration("d", "duration", "seconds (0: the preset's)", false, 0, "S",
                                     cmd);
    TCLAP::ValueArg<int> points("n", "points-per-frame", "points per frame (0: the preset's)",
                                false, 0, "N", cmd);
    TCLAP::ValueArg<std::string> out("o", "out", "output rawlog", false, "dyna_01.rawlog", "FILE",
                                     cmd);
    TCLAP::ValueArg<std::string> scenario(
        "c", "scenario",
        "INI file with a [scenario] section (a base preset or "
        "random + scenario keys, or a written <out>.scenario.ini)",
        false, "", "FILE", cmd);
    TCLAP::SwitchArg keys("", "scenario-keys", "print the [scenario] keys and exit", cmd);
    TCLAP::SwitchArg in_g("", "accel-in-g", "write accelerations in g", cmd);
    cmd.parse(argc, argv);
    if (keys.getValue()) {
      std::cout << freeinit::mrpt_glue::SimApp::scenarioKeys();
      return 0;
    }
    if (random.isSet() && (seed.isSet() || preset.isSet() || scenario.isSet()))
      throw std::invalid_argument("--random: not with --seed, --preset or --scenario");
    freeinit::mrpt_glue::SimApp app;
    app.params.preset = preset.getValue();
    app.params.seed = random.isSet() ? random.getValue() : seed.getValue();
    app.params.random = random.isSet();
    app.params.duration = duration.getValue();
    app.params.points_per_frame = points.getValue();
    app.params.output = out.getValue();
    app.params.accel_in_g = in_g.getValue();
    app.params.scenario_file = scenario.getValue();
    app.run(std::cout);
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "freeinit-sim: error: " << e.what() << "\n";
    return 1;
  }
}
