// freeinit-sim: writes a simulated preset or random scenario as a rawlog plus its ground truth.
#include <freeinit/mrpt_plugins/sim_app.h>

int main(int argc, char** argv) { return freeinit::mrpt_plugins::SimApp::main(argc, argv); }
