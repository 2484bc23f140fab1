// freeinit [<config.ini>] <input.rawlog> [--out DIR] [--start T | --every S | --starts FILE]
// [--check-all] [--salvage] [--no-index]: Free-Init on an MRPT rawlog.
#include <freeinit/mrpt_plugins/free_init_app.h>

int main(int argc, char** argv) { return freeinit::mrpt_plugins::FreeInitApp::main(argc, argv); }
