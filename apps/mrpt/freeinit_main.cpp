// freeinit <config.ini> <input.rawlog> [--out DIR]: Free-Init on an MRPT rawlog.
#include <freeinit/mrpt/FreeInitApp.h>
#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <unistd.h>

#include <iostream>

int main(int argc, char** argv) {
  try {
    TCLAP::CmdLine cmd(
        "freeinit: initial state (attitude, velocity, biases, gravity, static map) "
        "from the first instants of a Doppler LiDAR + IMU rawlog",
        ' ', "0.1");
    TCLAP::UnlabeledValueArg<std::string> ini("config", "INI configuration file", true, "",
                                              "config.ini", cmd);
    TCLAP::UnlabeledValueArg<std::string> rawlog("input", "input rawlog", true, "", "input.rawlog",
                                                 cmd);
    TCLAP::ValueArg<std::string> out("o", "out", "output folder", false, "freeinit_out", "DIR",
                                     cmd);
    TCLAP::SwitchArg quiet("q", "quiet", "no progress bar", cmd);
    cmd.parse(argc, argv);
    freeinit::mrpt_glue::FreeInitApp app;
    app.params.config_file = ini.getValue();
    app.params.rawlog = rawlog.getValue();
    app.params.out_dir = out.getValue();
    app.params.progress = !quiet.getValue();
    app.params.progress_terminal = isatty(STDOUT_FILENO) != 0;
    return app.run(std::cout);
  } catch (const std::exception& e) {
    std::cerr << "freeinit: error: " << e.what() << "\n";
    return 1;
  }
}
