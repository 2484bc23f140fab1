// freeinit-import-bag <bag> -c <config.ini> [-o out.rawlog] [--doppler-fit-csv FILE]: a ROS1 bag
// to a typed rawlog (BagImportApp, bag_import_app.h).
#include <freeinit/ros1/bag_import_app.h>

int main(int argc, char** argv) { return freeinit::mrpt_plugins::BagImportApp::main(argc, argv); }
