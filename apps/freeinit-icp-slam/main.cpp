// freeinit-icp-slam <icp.ini> <freeinit.ini> <input.rawlog> [--mode M] [--out DIR] [--export DIR]:
// MRPT icp-slam on a Doppler LiDAR + IMU rawlog, plain or seeded by Free-Init.
#include "icp_slam_app.h"

int main(int argc, char** argv) { return freeinit::apps::IcpSlamApp::main(argc, argv); }
