// freeinit-stream: plays a simulator preset or a rawlog as a live Doppler LiDAR + IMU UDP stream.
#include <freeinit/mrpt_plugins/stream_app.h>

int main(int argc, char** argv) { return freeinit::mrpt_plugins::StreamApp::main(argc, argv); }
