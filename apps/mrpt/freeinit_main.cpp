// freeinit <config.ini> <input.rawlog> [--out DIR] [--start T | --every S | --starts FILE]
// [--check-all] [--no-index]: Free-Init on an MRPT rawlog.
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
    TCLAP::ValueArg<double> start("", "start",
                                  "initialize with the records from T on: seconds after the first "
                                  "record, or a UNIX stamp if T > 1e8",
                                  false, 0, "T", cmd);
    TCLAP::ValueArg<double> every("", "every",
                                  "initialize every S seconds along the recording (from --start), "
                                  "each start in its own folder, with starts.csv/.md/.png",
                                  false, 0, "S", cmd);
    TCLAP::ValueArg<std::string> starts("", "starts",
                                        "initialize at each start in FILE (one per line, as "
                                        "--start), as --every does",
                                        false, "", "FILE", cmd);
    TCLAP::SwitchArg check_all("", "check-all",
                               "read and check the whole file (by default reading stops once "
                               "the state is ready)",
                               cmd);
    TCLAP::SwitchArg no_index("", "no-index",
                              "neither use nor write the seek index <input>.freeinit.idx", cmd);
    cmd.parse(argc, argv);
    freeinit::mrpt_glue::FreeInitApp app;
    app.params.config_file = ini.getValue();
    app.params.rawlog = rawlog.getValue();
    app.params.out_dir = out.getValue();
    app.params.progress = !quiet.getValue();
    app.params.progress_terminal = isatty(STDOUT_FILENO) != 0;
    if (start.isSet()) app.params.start = start.getValue();
    app.params.every = every.getValue();
    app.params.starts_file = starts.getValue();
    app.params.check_all = check_all.getValue();
    app.params.index.use = !no_index.getValue();
    app.params.command = "freeinit";
    for (int i = 1; i < argc; ++i) app.params.command += std::string(" ") + argv[i];
    return app.run(std::cout);
  } catch (const std::exception& e) {
    std::cerr << "freeinit: error: " << e.what() << "\n";
    return 1;
  }
}
