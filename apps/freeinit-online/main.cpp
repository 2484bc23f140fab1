// freeinit-online <config.ini> [--port N] [--out DIR]: Free-Init on a live Doppler LiDAR + IMU
// stream (docs/wire_format.md); writes initial_state.ini the moment the window closes.
#include "free_init_online_app.h"

int main(int argc, char** argv) { return freeinit::apps::FreeInitOnlineApp::main(argc, argv); }
