// freeinit [<config.ini>] <input.rawlog> [--out DIR] [--start T | --every S | --starts FILE]
// [--check-all] [--salvage] [--no-index]: Free-Init on an MRPT rawlog.
#include "free_init_app.h"

int main(int argc, char** argv) { return freeinit::apps::FreeInitApp::main(argc, argv); }
