// freeinit-stream: plays a simulator preset or a rawlog as a live Doppler LiDAR + IMU UDP stream.
#include "stream_app.h"

int main(int argc, char** argv) { return freeinit::apps::StreamApp::main(argc, argv); }
