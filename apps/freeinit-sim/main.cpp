// freeinit-sim: writes a simulated preset or random scenario as a rawlog plus its ground truth.
#include "sim_app.h"

int main(int argc, char** argv) { return freeinit::apps::SimApp::main(argc, argv); }
