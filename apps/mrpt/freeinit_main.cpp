// freeinit [<config.ini>] <input.rawlog> [--out DIR] [--start T | --every S | --starts FILE]
// [--check-all] [--salvage] [--no-index]: Free-Init on an MRPT rawlog.
#include <freeinit/mrpt_plugins/command_line.h>
#include <freeinit/mrpt_plugins/free_init_app.h>
#include <unistd.h>

#include <iostream>

int main(int argc, char** argv) {
  namespace plugins = freeinit::mrpt_plugins;
  namespace config = freeinit::config;
  plugins::CommandLine cli(
      "freeinit",
      "initial state (attitude, velocity, biases, gravity, static map) from the "
      "first instants of a Doppler LiDAR + IMU rawlog");
  const auto& ini = cli.positional("config.ini",
                                   "INI configuration file (ini/freeinit.ini documents every key); "
                                   "without it the defaults, the extrinsics from the rawlog",
                                   false);
  const auto& rawlog = cli.positional("input.rawlog", "input rawlog");
  const auto& out =
      cli.text("o", "out", "output folder (its earlier outputs are replaced)", "", "DIR",
               std::string(plugins::kDefaultOutDir) +
                   "; without <config.ini> a new folder for each run, "
                   "freeinit_out/<input>.<time>");
  const auto& quiet = cli.flag("q", "quiet",
                               "no progress bar and no listing of the effective configuration "
                               "(still written to effective_config.ini)");
  const auto& start = cli.number("", "start",
                                 "initialize with the records from T on: seconds after the first "
                                 "record, or a UNIX stamp if T > 1e8",
                                 0, config::atLeast(0), "T", "the first record");
  const auto& every = cli.number("", "every",
                                 "initialize every S seconds along the recording (from --start), "
                                 "each start in its own folder, with starts.csv/.md/.png",
                                 0, config::atLeast(0), "S", "off");
  const auto& starts = cli.text("", "starts",
                                "initialize at each start in FILE (one per line, as --start), "
                                "as --every does",
                                "", "FILE", "none");
  const auto& check_all = cli.flag("", "check-all",
                                   "read and check the whole file (by default reading stops once "
                                   "the state is ready)");
  const auto& salvage = cli.flag("", "salvage",
                                 "read a rawlog cut short (e.g. a recording when the power went "
                                 "off) up to its last whole record, with a warning naming where "
                                 "it stopped");
  const auto& no_index =
      cli.flag("", "no-index", "neither use nor write the seek index <input>.freeinit.idx");
  if (const auto code = cli.parse(argc, argv)) return *code;
  plugins::FreeInitApp app;
  app.params.config_file = ini.value;
  app.params.rawlog = rawlog.value;
  if (const auto problem = app.params.argumentsProblem(); !problem.empty())
    return cli.usageError(problem);
  return plugins::runMain(cli.program(), [&] {
    app.params.out_dir = out.given ? out.value : ini.given ? plugins::kDefaultOutDir : "";
    app.params.progress = !quiet.value;
    app.params.echo_config = !quiet.value;
    app.params.progress_terminal = isatty(STDOUT_FILENO) != 0;
    if (start.given) app.params.start = start.value;
    app.params.every = every.value;
    app.params.starts_file = starts.value;
    app.params.check_all = check_all.value;
    app.params.salvage = salvage.value;
    app.params.index.use = !no_index.value;
    app.params.command = "freeinit";
    for (int i = 1; i < argc; ++i) app.params.command += std::string(" ") + argv[i];
    return app.run(std::cout);
  });
}
