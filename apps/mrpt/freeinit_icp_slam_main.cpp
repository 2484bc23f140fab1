// freeinit-icp-slam <icp.ini> <freeinit.ini> <input.rawlog> [--mode M] [--out DIR] [--export DIR]:
// MRPT icp-slam on a Doppler LiDAR + IMU rawlog, plain or seeded by Free-Init.
#include <freeinit/mrpt_plugins/command_line.h>
#include <freeinit/mrpt_plugins/icp_slam_app.h>

#include <iostream>

int main(int argc, char** argv) {
  namespace plugins = freeinit::mrpt_plugins;
  plugins::CommandLine cli("freeinit-icp-slam",
                           "MRPT icp-slam (CMetricMapBuilderICP) started plain, seeded by "
                           "Free-Init's static map, pose and velocity, or seeded and fed with "
                           "Doppler-inertial odometry");
  const auto& icp_ini =
      cli.positional("icp_slam.ini", "icp-slam INI ([MappingApplication], [ICP], [freeinit_scan])");
  const auto& fi_ini = cli.positional("freeinit.ini", "Free-Init INI");
  const auto& rawlog = cli.positional("input.rawlog", "input rawlog");
  const auto& mode =
      cli.choice("m", "mode", "icp-slam start", "all", {"plain", "seeded", "odometry", "all"});
  const auto& out = cli.text("o", "out", "output folder", "icp_slam_out", "DIR");
  const auto& exp = cli.text("e", "export",
                             "also write <DIR>/<mode>.rawlog + <mode>.ini for the stock icp-slam "
                             "app",
                             "", "DIR", "none");
  const auto& no_png = cli.flag("", "no-png", "do not render trajectories.png");
  if (const auto code = cli.parse(argc, argv)) return *code;
  return plugins::runMain(cli.program(), [&] {
    plugins::IcpSlamApp app;
    app.params.icp_ini = icp_ini.value;
    app.params.freeinit_ini = fi_ini.value;
    app.params.rawlog = rawlog.value;
    app.params.out_dir = out.value;
    app.params.export_dir = exp.value;
    app.params.snapshot = !no_png.value;
    if (mode.value != "all") app.params.modes = {plugins::seedModeFromString(mode.value)};
    return app.run(std::cout);
  });
}
