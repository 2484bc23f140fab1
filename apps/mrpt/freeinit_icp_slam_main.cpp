// freeinit-icp-slam <icp.ini> <freeinit.ini> <input.rawlog> [--mode M] [--out DIR] [--export DIR]:
// MRPT icp-slam on a Doppler LiDAR + IMU rawlog, plain or seeded by Free-Init.
#include <freeinit/mrpt/IcpSlamApp.h>
#include <mrpt/3rdparty/tclap/CmdLine.h>

#include <iostream>

int main(int argc, char** argv) {
  try {
    TCLAP::CmdLine cmd(
        "freeinit-icp-slam: MRPT icp-slam (CMetricMapBuilderICP) started plain, seeded by "
        "Free-Init's static map, pose and velocity, or seeded and fed with Doppler-inertial "
        "odometry",
        ' ', "0.1");
    TCLAP::UnlabeledValueArg<std::string> icp_ini(
        "icp_ini", "icp-slam INI ([MappingApplication], [ICP], [freeinit_scan])", true, "",
        "icp_slam.ini", cmd);
    TCLAP::UnlabeledValueArg<std::string> fi_ini("freeinit_ini", "Free-Init INI", true, "",
                                                 "freeinit.ini", cmd);
    TCLAP::UnlabeledValueArg<std::string> rawlog("input", "input rawlog", true, "", "input.rawlog",
                                                 cmd);
    TCLAP::ValueArg<std::string> mode("m", "mode", "plain, seeded, odometry or all (default)",
                                      false, "all", "MODE", cmd);
    TCLAP::ValueArg<std::string> out("o", "out", "output folder", false, "icp_slam_out", "DIR",
                                     cmd);
    TCLAP::ValueArg<std::string> exp("e", "export",
                                     "also write <DIR>/<mode>.rawlog + <mode>.ini for the stock "
                                     "icp-slam app",
                                     false, "", "DIR", cmd);
    TCLAP::SwitchArg no_png("", "no-png", "do not render trajectories.png", cmd);
    cmd.parse(argc, argv);
    freeinit::mrpt_glue::IcpSlamApp app;
    app.params.icp_ini = icp_ini.getValue();
    app.params.freeinit_ini = fi_ini.getValue();
    app.params.rawlog = rawlog.getValue();
    app.params.out_dir = out.getValue();
    app.params.export_dir = exp.getValue();
    app.params.snapshot = !no_png.getValue();
    if (mode.getValue() != "all")
      app.params.modes = {freeinit::mrpt_glue::seedModeFromString(mode.getValue())};
    return app.run(std::cout);
  } catch (const std::exception& e) {
    std::cerr << "freeinit-icp-slam: error: " << e.what() << "\n";
    return 1;
  }
}
