// freeinit <config.ini> <input.rawlog> [--out DIR]: Free-Init on an MRPT rawlog.
#include <freeinit/mrpt/CommandLine.h>
#include <freeinit/mrpt/FreeInitApp.h>
#include <unistd.h>

#include <iostream>

int main(int argc, char** argv) {
  namespace glue = freeinit::mrpt_glue;
  glue::CommandLine cli("freeinit",
                        "initial state (attitude, velocity, biases, gravity, static map) from the "
                        "first instants of a Doppler LiDAR + IMU rawlog");
  const auto& ini = cli.positional("config.ini", "INI configuration file (ini/freeinit.ini)");
  const auto& rawlog = cli.positional("input.rawlog", "input rawlog");
  const auto& out = cli.text("o", "out", "output folder", "freeinit_out", "DIR");
  const auto& quiet = cli.flag("q", "quiet", "no progress bar");
  if (const auto code = cli.parse(argc, argv)) return *code;
  return glue::runMain(cli.program(), [&] {
    glue::FreeInitApp app;
    app.params.config_file = ini.value;
    app.params.rawlog = rawlog.value;
    app.params.out_dir = out.value;
    app.params.progress = !quiet.value;
    app.params.progress_terminal = isatty(STDOUT_FILENO) != 0;
    return app.run(std::cout);
  });
}
