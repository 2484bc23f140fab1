// freeinit-import-bag <bag> -c <config.ini> [-o out.rawlog] [--doppler-fit-csv FILE]: a ROS1 bag
// to a typed rawlog (BagImportApp, bag_import_app.h).
#include "bag_import_app.h"

int main(int argc, char** argv) { return freeinit::apps::BagImportApp::main(argc, argv); }
