// freeinit-import-bag <bag> -c <config.ini> [-o out.rawlog]: a ROS1 bag to a typed rawlog.
#include <freeinit/ros1/BagImportApp.h>
#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <unistd.h>

#include <iostream>

int main(int argc, char** argv) {
  try {
    TCLAP::CmdLine cmd(
        "freeinit-import-bag: a ROS1 bag (sensor_msgs/Imu + sensor_msgs/PointCloud2 with "
        "per-point Doppler and time) to a rawlog for freeinit",
        ' ', "0.1");
    TCLAP::UnlabeledValueArg<std::string> bag("bag", "input ROS1 bag", true, "", "input.bag", cmd);
    TCLAP::ValueArg<std::string> config("c", "config",
                                        "INI with [bag_import] and [extrinsics] "
                                        "(see ini/import_bag.ini)",
                                        true, "", "FILE", cmd);
    TCLAP::ValueArg<std::string> out("o", "out", "output rawlog (default: <bag>.rawlog)", false, "",
                                     "FILE", cmd);
    TCLAP::ValueArg<std::string> fit_csv(
        "", "doppler-fit-csv",
        "also write each imported scan's sensor velocity fitted from its Doppler alone (no IMU; "
        "[doppler_fit] of the INI) to FILE",
        false, "", "FILE", cmd);
    TCLAP::SwitchArg quiet("q", "quiet", "no progress bar", cmd);
    cmd.parse(argc, argv);
    freeinit::mrpt_glue::BagImportApp app;
    app.params.bag = bag.getValue();
    app.params.config_file = config.getValue();
    app.params.output = out.getValue();
    app.params.doppler_fit_csv = fit_csv.getValue();
    app.params.progress = !quiet.getValue();
    app.params.progress_terminal = isatty(STDOUT_FILENO) != 0;
    return app.run(std::cout);
  } catch (const std::exception& e) {
    std::cerr << "freeinit-import-bag: error: " << e.what() << "\n";
    return 1;
  }
}
