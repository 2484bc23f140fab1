// freeinit-eval-rawlog <config.ini> <a.rawlog> [b.rawlog ...]: Free-Init and the baselines on
// recorded rawlogs with ground truth (EvalRawlogApp, eval_rawlog_app.h).
#include "eval_rawlog_app.h"

int main(int argc, char** argv) { return freeinit::apps::EvalRawlogApp::main(argc, argv); }
