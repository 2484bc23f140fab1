// freeinit-import-bag <bag> -c <config.ini> [-o out.rawlog] [--doppler-fit-csv FILE]: a ROS1 bag
// to a typed rawlog.
#include <freeinit/mrpt_plugins/command_line.h>
#include <freeinit/ros1/bag_import_app.h>
#include <unistd.h>

#include <iostream>

int main(int argc, char** argv) {
  namespace plugins = freeinit::mrpt_plugins;
  plugins::CommandLine cli("freeinit-import-bag",
                           "a ROS1 bag (sensor_msgs/Imu + sensor_msgs/PointCloud2 with per-point "
                           "Doppler and time) to a rawlog for freeinit");
  const auto& bag = cli.positional("input.bag", "input ROS1 bag");
  const auto& config = cli.requiredText(
      "c", "config",
      "INI with [bag_import], [extrinsics] and optionally [doppler_fit] (see ini/import_bag.ini)",
      "FILE");
  const auto& out = cli.text("o", "out", "output rawlog", "", "FILE", "<bag>.rawlog");
  const auto& fit_csv = cli.text("", "doppler-fit-csv",
                                 "also write each imported scan's sensor velocity fitted from its "
                                 "Doppler alone (no IMU; [doppler_fit] of the INI) to FILE",
                                 "", "FILE", "none");
  const auto& quiet = cli.flag("q", "quiet", "no progress bar");
  if (const auto code = cli.parse(argc, argv)) return *code;
  return plugins::runMain(cli.program(), [&] {
    plugins::BagImportApp app;
    app.params.bag = bag.value;
    app.params.config_file = config.value;
    app.params.output = out.value;
    app.params.doppler_fit_csv = fit_csv.value;
    app.params.progress = !quiet.value;
    app.params.progress_terminal = isatty(STDOUT_FILENO) != 0;
    return app.run(std::cout);
  });
}
